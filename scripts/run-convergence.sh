#!/usr/bin/env bash
# GRM convergence study (docs/getting-started.md, "Convergence"): builds screwfem in Release (build/release),
# runs the rigid GRM with 2, 4, 8 and 16 elements per soft body and several steps into
# out/convergence/, and writes the table to out/convergence/table.md (also printed).
# Run as root if dependencies may be missing.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=build/release
jobs=$(nproc 2> /dev/null || echo 2)

bash scripts/setup-deps.sh
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$build_dir" -j"$jobs" --target screwfem_cli
mkdir -p out/convergence
/usr/bin/python3 tools/grm_convergence.py "$build_dir/app/screwfem" out/convergence "$@" \
  | tee out/convergence/table.md
