#!/usr/bin/env bash
# The test job (README.md, second command; docs/getting-started.md; also .ci/run):
#   1. installs missing Debian packages (those the Release build needs first; the rest while it
#      compiles);
#   2. Release build in build/release, its ctest suite, and every example program
#      (build/release/examples/**/*_example, run from the repository root without arguments);
#   3. AddressSanitizer + UndefinedBehaviorSanitizer build in build/asan (clang, with the
#      libFuzzer harnesses of tests/fuzz) and its ctest suite: every example scene's first
#      steps, the fuzz regression corpus, and the solve, io, elements, validation, linalg and
#      build test programs less their longest tests (the whole suite under the sanitizers is
#      scripts/run-sanitizers.sh, on demand);
#   4. the three fuzz targets (parse, build, run) in two concurrent slots for
#      SCREWFEM_FUZZ_SECONDS (default 20; run_fuzzers) on the seed corpus (the example scenes,
#      tests/data/, tests/fuzz/seeds/NAME/, tests/fuzz/regressions/NAME/): any crash, sanitizer
#      report, leak, timeout (10 s per input) or out-of-memory (1024 MB) fails the job, and
#      the failing input is copied into tests/fuzz/regressions/NAME/ (commit it: ctest
#      replays that corpus in every build). Longer campaigns: scripts/fuzz-campaign.sh.
#   5. the lint (scripts/lint.sh): every C++ file as .clang-format lays it out, and commit
#      subjects of at most 72 characters with a body; a broken rule counts as one failure.
# Runs every phase even after a failure (except the sanitizer build when the Release build
# failed), prints the time of each phase, and ends with the line "N passed, M failed" summed
# over both ctest runs and the examples; a failed build or a ctest run without a summary counts
# as one failure. Exits non-zero when M > 0. Run as root (installing packages needs it).
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

release_dir=build/release
jobs=$(nproc 2> /dev/null || echo 2)
[[ $jobs -ge 2 ]] || jobs=2

passed=0
failed=0
failures=()

source scripts/phase-timing.sh
fail() {
  failed=$((failed + 1))
  failures+=("$1")
  echo "!! FAILED: $1" >&2
}

# configure_and_build LABEL DIR CMAKE_ARGS... -> status 0 on success
configure_and_build() {
  local label=$1 dir=$2
  shift 2
  begin "build ($label)"
  local status=0
  cmake -S . -B "$dir" "$@" && cmake --build "$dir" -j"$jobs" || status=1
  end "build ($label)"
  [[ $status -eq 0 ]] || fail "build ($label)"
  return $status
}

# run_ctest LABEL DIR [CTEST_ARGS...]: runs the suite and adds ctest's "X tests failed out of Y"
# to the counts.
run_ctest() {
  local label=$1 dir=$2 log=$2/ctest.log status summary total bad
  shift 2
  begin "ctest ($label)"
  ctest --test-dir "$dir" -j"$jobs" --output-on-failure --no-tests=error "$@" 2>&1 | tee "$log"
  status=${PIPESTATUS[0]}
  end "ctest ($label)"
  summary=$(grep -Eo '[0-9]+ tests? failed out of [0-9]+' "$log" | tail -n 1)
  if [[ -z "$summary" ]]; then
    fail "ctest ($label): no test summary (exit status $status)"
    return
  fi
  bad=${summary%% *}
  total=${summary##* }
  passed=$((passed + total - bad))
  failed=$((failed + bad))
  if [[ $bad -gt 0 ]]; then
    failures+=("ctest ($label): $bad of $total tests")
  elif [[ $status -ne 0 ]]; then
    fail "ctest ($label): exit status $status"
  fi
}

# run_examples DIR: every *_example program under DIR/examples; the statics example must exist.
run_examples() {
  local dir=$1 logs=$1/example-logs exe name status
  begin "examples (Release)"
  mkdir -p "$logs"
  local examples=()
  if [[ -d "$dir/examples" ]]; then
    mapfile -t examples < <(find "$dir/examples" -path '*/CMakeFiles' -prune -o \
      -type f -name '*_example' -perm -u+x -print | sort)
  fi
  if [[ ! -x "$dir/examples/statics/screwfem_statics_example" ]]; then
    fail "example statics: $dir/examples/statics/screwfem_statics_example was not built"
  fi
  for exe in "${examples[@]}"; do
    name=$(basename "$exe")
    timeout 600 "$exe" > "$logs/$name.log" 2>&1
    status=$?
    if [[ $status -eq 0 ]]; then
      passed=$((passed + 1))
      echo "example $name: passed (output in $logs/$name.log)"
    else
      tail -n 40 "$logs/$name.log"
      fail "example $name: exit status $status (output in $logs/$name.log)"
    fi
  done
  end "examples (Release)"
}

# fuzz_target DIR NAME SECONDS: one libFuzzer target on its seed corpus (the example scenes,
# tests/data/, tests/fuzz/seeds/NAME/ and tests/fuzz/regressions/NAME/) for SECONDS; its log,
# artifacts and exit status go to DIR/fuzz/NAME/.
fuzz_target() {
  local dir=$1 name=$2 seconds=$3 work=$1/fuzz/$2 seeds=()
  rm -rf "$work"
  mkdir -p "$work/corpus" "$work/artifacts"
  [[ -d "tests/fuzz/seeds/$name" ]] && seeds+=("tests/fuzz/seeds/$name")
  # The first directory receives new inputs; the others are read-only seeds.
  "$dir/tests/fuzz/screwfem_fuzz_$name" "$work/corpus" examples/*/ tests/data "${seeds[@]}" \
    "tests/fuzz/regressions/$name" -max_total_time="$seconds" -timeout=10 \
    -rss_limit_mb=1024 -max_len=65536 -print_final_stats=1 \
    -artifact_prefix="$work/artifacts/" > "$work/log.txt" 2>&1
  echo $? > "$work/status"
}

# run_fuzzers DIR: the three libFuzzer targets in two concurrent slots (one per core) for
# SCREWFEM_FUZZ_SECONDS (default 20) of wall time: the run target (the whole run path, the
# slowest per input) in one slot for all of it, parse then build in the other for half of it
# each. One pass or one failure per target in the counts.
run_fuzzers() {
  local dir=$1 seconds=${SCREWFEM_FUZZ_SECONDS:-20} name work status
  local half=$(((seconds + 1) / 2))
  begin "fuzzing (2 slots x ${seconds} s)"
  (
    fuzz_target "$dir" parse "$half"
    fuzz_target "$dir" build "$half"
  ) &
  local slot_a=$!
  fuzz_target "$dir" run "$seconds" &
  local slot_b=$!
  wait "$slot_a" "$slot_b"
  for name in parse build run; do
    work=$dir/fuzz/$name
    status=$(cat "$work/status" 2> /dev/null || echo 1)
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec)' "$work/log.txt" |
      sed "s/^/fuzz $name: /"
    if [[ $status -eq 0 ]]; then
      passed=$((passed + 1))
      echo "fuzz $name: passed (log in $work/log.txt)"
    else
      tail -n 60 "$work/log.txt"
      local f
      for f in "$work"/artifacts/*; do
        [[ -e "$f" ]] || continue
        cp "$f" "tests/fuzz/regressions/$name/"
        echo "fuzz $name: failing input kept as tests/fuzz/regressions/$name/$(basename "$f")"
      done
      fail "fuzz $name: exit status $status (log in $work/log.txt)"
    fi
  done
  end "fuzzing (2 slots x ${seconds} s)"
}

total_start=$(now_us)

begin "dependencies (build)"
bash scripts/setup-deps.sh build || { echo "run-tests: dependencies missing; stopping" >&2; exit 1; }
end "dependencies (build)"
# The other packages (clang, Chromium, the Python tools' packages) are downloaded and installed
# while the Release tree compiles; the job waits for them before the first test.
mkdir -p build
bash scripts/setup-deps.sh rest > build/setup-deps-rest.log 2>&1 &
rest_pid=$!
wait_for_rest() {
  [[ -n "${rest_pid:-}" ]] || return 0
  begin "dependencies (rest, waited for)"
  local status=0
  wait "$rest_pid" || status=$?
  rest_pid=
  end "dependencies (rest, waited for)"
  cat build/setup-deps-rest.log
  if [[ $status -ne 0 ]]; then
    echo "run-tests: installing the remaining dependencies failed; stopping" >&2
    exit 1
  fi
}

# The benchmarks are not run here (scripts/run-bench.sh builds them): not built either.
configure_and_build "Release" "$release_dir" -DCMAKE_BUILD_TYPE=Release \
  -DSCREWFEM_BUILD_BENCH=OFF
release_status=$?
wait_for_rest
# The house rules a machine can check: the C++ layout (.clang-format) and the commit messages.
begin "lint"
bash scripts/lint.sh || fail "lint (scripts/lint.sh)"
end "lint"
if [[ $release_status -eq 0 ]]; then
  run_ctest "Release" "$release_dir"
  run_examples "$release_dir"
  release_built=1
else
  release_built=0
fi

if [[ $release_built -eq 1 ]]; then
  source scripts/sanitizer-config.sh
  # The sanitizer stage (scripts/sanitizer-config.sh) instruments the product: the libraries,
  # the command-line program and the fuzz harnesses. It runs
  #  - every example scene's first steps through the instrumented program (tests
  #    sanitizer_scene_*: rods, rigid bodies, joints, tendons, pressure, rest curvature,
  #    contact, run-time inputs, and the files they write);
  #  - the regression corpus and seeds of the fuzzers, then the three fuzzers (run_fuzzers);
  #  - six test programs ($asan_stage_programs): tests/solve (statics, dynamics, tendons),
  #    tests/io (scenes, runs, the files, the CLI, limits), tests/elements (the kernels,
  #    contact, tendons), tests/validation (closed-form problems), tests/linalg and
  #    tests/build, less their longest tests (tests/sanitize/long_tests.txt).
  # lie, model, assemble and alloc, and the long tests, run in the Release suite above, and
  # under the sanitizers in scripts/run-sanitizers.sh, on demand. Measured on the loaded
  # 2-core machine (CPU time; it ran about 1.2 times its idle value): the four programs added
  # 158 CPU-s to the build (io 54, validation 46, elements 45, solve 12), and the stage's 429
  # tests took 107 CPU-s; projected on 2 idle cores, about +66 s of build and +55 s of tests,
  # less the 20 s of the viewer's Chromium tests, which no longer run here: about 14.3 min in
  # all (docs/fuzzing.md, docs/maintainers.md).
  if configure_and_build "ASan+UBSan" "$asan_dir" "${asan_cmake_args[@]}" \
      -DSCREWFEM_TEST_PROGRAMS="$asan_stage_programs"; then
    run_ctest "ASan+UBSan" "$asan_dir" -E "$asan_always_excluded|$asan_stage_excluded"
    run_fuzzers "$asan_dir"
  fi
else
  echo "== sanitizer build skipped: the Release build failed"
fi

total_us=$(($(now_us) - total_start))
echo
echo "Phase timings:"
printf '  %s\n' "${timings[@]}"
printf '  %-34s %8d.%01d s\n' "total" $((total_us / 1000000)) $((total_us % 1000000 / 100000))
if [[ ${#failures[@]} -gt 0 ]]; then
  echo "Failures:"
  printf '  %s\n' "${failures[@]}"
fi
echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
