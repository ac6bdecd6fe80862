# The sanitizer build, shared by scripts/run-tests.sh (its sanitizer stage) and
# scripts/run-sanitizers.sh (the whole suite under the sanitizers); sourced, not run.
#
# RelWithDebInfo without -DNDEBUG: optimised with assert() and eigen_assert active, as
# cmake/ScrewfemTargets.cmake intends for the sanitizer build. -O1 -g1 (line tables, enough for
# the sanitizers' stack traces) compiles in less than half the time of -O2 -g with the
# sanitizers on. SCREWFEM_NATIVE=OFF: the portable instruction set (the Release build uses the
# machine's), so the code runs on both code paths of Eigen's vectorisation. Clang (not GCC): it
# provides libFuzzer, so one tree serves the sanitizer tests and the fuzzers; it also compiles
# the sanitizer build faster than GCC (docs/maintainers.md, "Fuzzing").
asan_dir=build/asan
asan_cmake_args=(-DSCREWFEM_SANITIZE=ON -DCMAKE_CXX_COMPILER=clang++ -DSCREWFEM_FUZZ=ON
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1"
  -DSCREWFEM_BUILD_BENCH=OFF -DSCREWFEM_BUILD_EXAMPLES=OFF -DSCREWFEM_NATIVE=OFF)
# The sanitizers also run inside the build (gtest_discover_tests executes the test programs).
export ASAN_OPTIONS=detect_leaks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
# Python code, with nothing of screwfem's C++ in it but the run that makes its input: the
# tests of the Python tools (plots, the viewer in Chromium, the VTK reader) are never run
# under the sanitizers.
asan_always_excluded='^viewer_|^tools_|^Cli\.Plot(DrawsPoints|Animate)'
# The test command's sanitizer stage (scripts/run-tests.sh): the test programs it builds (the
# solver, io with the scenes, contact and tendons, the element kernels and the validation
# problems, besides linalg and build; not lie, model, assemble and alloc), and the tests of
# them it leaves out, the longest (tests/sanitize/long_tests.txt; each name a whole-name
# regex). scripts/run-sanitizers.sh builds every program and runs every test.
asan_stage_programs="linalg;build;solve;elements;validation;io"
asan_stage_excluded=$(grep -Ev '^(#|$)' tests/sanitize/long_tests.txt | sed -e 's/\./\\./g' \
  -e 's/.*/^&$/' | paste -sd '|')
