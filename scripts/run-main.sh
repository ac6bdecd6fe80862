#!/usr/bin/env bash
# The main job (README.md, "Quick start", first command): installs missing Debian packages,
# builds screwfem in Release into build/release, runs the statics example and the three GRM
# cases, and plots the GRM results, writing everything to out/. Run as root (installing
# packages needs it).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=build/release
jobs=$(nproc 2> /dev/null || echo 2)

source scripts/phase-timing.sh

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

# The GRM of the method paper in its three cases (examples/grm, ../shared/grm.md): each run
# writes points.csv, joints.csv, summary.json and ParaView frames into out/grm_<case>/.
screwfem=$build_dir/app/screwfem
cases=(rigid soft_k soft_kd)
run_dirs=()
for c in "${cases[@]}"; do
  begin "GRM $c (0 to 2 s)"
  "$screwfem" run "examples/grm/grm_$c.yaml" -o "out/grm_$c" --quiet --force
  end "GRM $c (0 to 2 s)"
  run_dirs+=("out/grm_$c")
done

# Figures: displacement, velocity and acceleration of P8 and P4 with the three cases overlaid
# (the paper's Fig. 4), every joint, and 3D snapshots of each case (Fig. 3).
begin "GRM figures"
"$screwfem" plot "${run_dirs[@]}" -o out/figures --times 0,0.5,1,1.5,2
end "GRM figures"

echo
echo "Phase timings:"
printf '  %s\n' "${timings[@]}"
echo "Output written to out/statics.txt, out/grm_{rigid,soft_k,soft_kd}/ and out/figures/"
