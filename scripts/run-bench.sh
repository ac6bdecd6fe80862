#!/usr/bin/env bash
# Builds the benchmarks in Release (build/release), runs them and rewrites bench/RESULTS.md
# from bench/results.json (README.md, "Benchmarks"). Extra arguments go to the benchmark
# program, e.g. --benchmark_filter=Solve. Run as root if dependencies may be missing.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=build/release
jobs=$(nproc 2> /dev/null || echo 2)

bash scripts/setup-deps.sh
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release
cmake --build "$build_dir" -j"$jobs" --target screwfem_bench_statics

# Median of 5 repetitions: the numbers stay stable on a machine with other load.
"$build_dir/bench/screwfem_bench_statics" --benchmark_format=console \
  --benchmark_out=bench/results.json --benchmark_out_format=json \
  --benchmark_repetitions=5 --benchmark_report_aggregates_only=true "$@"

revision=$(git describe --always --dirty 2> /dev/null || echo unknown)
/usr/bin/python3 bench/make_results.py bench/results.json bench/RESULTS.md \
  "bash scripts/run-bench.sh" "$revision"
echo "Wrote bench/results.json and bench/RESULTS.md"
