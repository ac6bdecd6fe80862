#!/usr/bin/env bash
# Builds the benchmarks in Release (build/release), runs them and rewrites bench/RESULTS.md
# from their JSON results (docs/benchmarks.md):
#   screwfem_bench_statics   -> bench/results_statics.json   (rod assembly and solve)
#   screwfem_bench_dynamics  -> bench/results_dynamics.json  (GRM runs, rod time steps)
#   screwfem_bench_outputs   -> bench/results_outputs.json   (cost of a run's outputs)
#   screwfem_bench_tendons   -> bench/results_tendons.json   (cost of tendons on a rod)
#   screwfem_bench_contact   -> bench/results_contact.json   (cost of contact along a rod)
#   screwfem_bench_solver    -> bench/results_solver.json    (banded against sparse LU; its own
#                               JSON and interleaving, not Google Benchmark; about 1 minute)
#   screwfem_bench_parallel  -> bench/results_parallel.json  (one thread against two)
#   screwfem_bench_pairs     -> bench/results_pairs.json     (spheres on a plane and crossing
#                               rods: contact pairs in the sparse pattern; its own JSON and
#                               interleaving; about 2 minutes)
#   screwfem_bench_mujoco_box -> bench/results_mujoco_box.json (a box dropped and sliding,
#                               against MuJoCo; its own JSON and interleaving; built when
#                               libmujoco-dev is found; not in the default set, about 2 minutes)
#   bench/pyelastica_bench.py -> bench/results_pyelastica_E*.json (a rod sliding to rest, against
#                               PyElastica; run by hand with --pyelastica DIR, a checkout of its
#                               source; make_results.py renders the file when it is there)
#   vector_env               -> its own section of bench/RESULTS.md (bench/python_vector_env.py:
#                               screwfem.VectorEnv's steps per second at 1, 2, 4 copies; builds
#                               the Python module; not in the default set)
# SCREWFEM_BENCH selects the programs (default "statics dynamics outputs tendons contact solver
# parallel pairs"); the results file of a program not run (or whose benchmarks a filter left out
# entirely) is kept and reported with its own date and revision. Extra arguments go to every Google Benchmark
# program run, e.g.
# SCREWFEM_BENCH=dynamics bash scripts/run-bench.sh --benchmark_filter=Rod.
# Run as root if dependencies may be missing.
# Takes about 1 minute on 2 cores (plus the build).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=build/release
jobs=$(nproc 2> /dev/null || echo 2)
programs=${SCREWFEM_BENCH:-statics dynamics outputs tendons contact solver parallel pairs}
for p in $programs; do
  case $p in
    statics | dynamics | outputs | tendons | contact | solver | parallel | pairs | mujoco_box | vector_env) ;;
    *) echo "run-bench.sh: unknown benchmark program '$p' in SCREWFEM_BENCH" >&2; exit 2 ;;
  esac
done

bash scripts/setup-deps.sh bench
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSCREWFEM_BUILD_BENCH=ON
targets=()
benchmarks=()
for p in $programs; do
  if [[ $p == vector_env ]]; then
    targets+=(_screwfem)
  else
    targets+=("screwfem_bench_$p")
    benchmarks+=("$p")
  fi
done
cmake --build "$build_dir" -j"$jobs" --target "${targets[@]}"

revision=$(git describe --always --dirty 2> /dev/null || echo unknown)
# The instruction set the build used (CMakeLists.txt, SCREWFEM_NATIVE), as one word for the
# benchmark context (its values take no '=' or ','); make_results.py spells it out.
cache=$build_dir/CMakeCache.txt
if ! grep -q '^SCREWFEM_NATIVE:BOOL=ON' "$cache"; then
  isa=portable
elif grep -q '^SCREWFEM_HAS_MARCH_NATIVE_NO_AVX512:INTERNAL=1' "$cache"; then
  isa=native-no-avx512
elif grep -q '^SCREWFEM_HAS_MARCH_NATIVE:INTERNAL=1' "$cache"; then
  isa=native
else
  isa=portable
fi
for p in "${benchmarks[@]}"; do
  out=bench/results_$p.json
  tmp=bench/results_$p.json.tmp
  rm -f "$tmp"
  if [[ $p == solver || $p == pairs ]]; then
    "$build_dir/bench/screwfem_bench_$p" "$tmp" && mv "$tmp" "$out"
    continue
  fi
  if [[ $p == mujoco_box ]]; then
    "$build_dir/bench/screwfem_bench_$p" --json "$tmp" --revision "$revision" && mv "$tmp" "$out"
    continue
  fi
  # statics: median of 5 repetitions, so the numbers stay stable on a machine with other
  # load. dynamics: each benchmark sets its own iterations and repetitions (fewer for the
  # slow cases: a GRM run takes seconds, a 10000-element rod step about half a second).
  repetitions=()
  if [[ $p == statics ]]; then repetitions=(--benchmark_repetitions=5); fi
  # tendons, contact, dynamics: the variants' repetitions alternate (the same machine load for
  # all; dynamics: the fixed and the error-controlled rigid GRM).
  # parallel: threads = 1 and 2 alternate.
  if [[ $p == tendons || $p == contact || $p == dynamics || $p == parallel ]]; then
    repetitions=(--benchmark_enable_random_interleaving=true)
  fi
  "$build_dir/bench/screwfem_bench_$p" --benchmark_format=console \
    --benchmark_out="$tmp" --benchmark_out_format=json \
    --benchmark_context=revision="$revision",isa="$isa" \
    "${repetitions[@]}" --benchmark_report_aggregates_only=true "$@"
  # An empty file: the filter matched nothing in this program; keep its previous results.
  if [[ -s $tmp ]]; then mv "$tmp" "$out"; else rm -f "$tmp"; fi
done

/usr/bin/python3 bench/make_results.py bench/RESULTS.md "bash scripts/run-bench.sh" "$revision" \
  bench/results_statics.json bench/results_dynamics.json bench/results_outputs.json \
  bench/results_tendons.json bench/results_contact.json bench/results_solver.json \
  bench/results_parallel.json bench/results_pairs.json bench/results_mujoco_box.json \
  bench/results_pyelastica_*.json
echo "Wrote bench/RESULTS.md from bench/results_{statics,dynamics,outputs,tendons,contact,solver,parallel,pairs}.json"
# After make_results.py, which keeps the section the Python benchmark replaces. It exits 1 when
# its target is missed (on a loaded machine); the table is written either way.
if [[ " $programs " == *" vector_env "* ]]; then
  PYTHONPATH=$build_dir/python /usr/bin/python3 bench/python_vector_env.py ||
    echo "run-bench.sh: python_vector_env.py: target not met (see bench/RESULTS.md)" >&2
fi
