#!/usr/bin/env bash
# The main job (README.md, "Quick start", first command): installs missing Debian packages,
# builds screwfem in Release into build/release and runs the examples, writing their output
# to out/. Run as root (installing packages needs it).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=build/release
jobs=$(nproc 2> /dev/null || echo 2)

# Phase timing (bash's EPOCHREALTIME; no external tools).
now_us() { echo "${EPOCHREALTIME//[.,]/}"; }
timings=()
phase_start=0
begin() { echo "== $1"; phase_start=$(now_us); }
end() {
  local us=$(($(now_us) - phase_start)) t
  t=$(printf '%d.%01d s' $((us / 1000000)) $((us % 1000000 / 100000)))
  timings+=("$(printf '%-30s %10s' "$1" "$t")")
  echo "== $1: $t"
}

begin "dependencies"
bash scripts/setup-deps.sh
end "dependencies"

begin "configure (Release)"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release
end "configure (Release)"

begin "build (Release, -j$jobs)"
cmake --build "$build_dir" -j"$jobs"
end "build (Release, -j$jobs)"

mkdir -p out

# Statics example: helical rod statics with load stepping; the program prints its results.
begin "statics example"
statics_example=$build_dir/examples/statics/screwfem_statics_example
if [[ ! -x "$statics_example" ]]; then
  echo "run-main: $statics_example was not built" >&2
  exit 1
fi
"$statics_example" | tee out/statics.txt
end "statics example"

# GRM example: to be added here once the CLI runs scene files (screwfem run
# examples/grm/<scene>.yaml -o out/..., then screwfem plot on that output).

echo
echo "Phase timings:"
printf '  %s\n' "${timings[@]}"
echo "Output written to out/statics.txt"
