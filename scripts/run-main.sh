#!/usr/bin/env bash
# The main job (README.md, first command; docs/getting-started.md): installs missing Debian packages,
# builds what it runs (the screwfem program, the statics example and the Python module) in
# Release into build/main, runs the statics example and the GRM cases, plots the GRM results,
# writes a browser viewer per case, and runs the closed-loop soft arm from Python, recorded,
# everything into out/. Run as root (installing packages needs it).
#
# build/main, not the test job's build/release: the main job configures without the test
# suite and the benchmarks, and CMake keeps such options in its cache, so a shared directory
# would leave the test job's next configure without its tests.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

build_dir=build/main
jobs=$(nproc 2> /dev/null || echo 2)

source scripts/phase-timing.sh

begin "dependencies"
bash scripts/setup-deps.sh main
end "dependencies"

begin "configure (Release)"
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DSCREWFEM_BUILD_TESTS=OFF \
  -DSCREWFEM_BUILD_BENCH=OFF -DSCREWFEM_BUILD_PYTHON=ON
end "configure (Release)"

begin "build (Release, -j$jobs)"
cmake --build "$build_dir" -j"$jobs" --target screwfem_cli screwfem_statics_example _screwfem
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

# The GRM of the method paper (examples/grm; docs/getting-started.md, "The GRM example"): the rigid case, and the soft
# cases in both readings (series-elastic actuated joints, and springs in parallel with
# prescribed ones). Each run writes points.csv, joints.csv, joints.json, summary.json and
# ParaView frames into out/grm_<case>/.
screwfem=$build_dir/app/screwfem
cases=(rigid soft_k soft_kd soft_k_parallel soft_kd_parallel)
run_dirs=()
for c in "${cases[@]}"; do
  begin "GRM $c (0 to 2 s)"
  "$screwfem" run "examples/grm/grm_$c.yaml" -o "out/grm_$c" --quiet --force
  end "GRM $c (0 to 2 s)"
  run_dirs+=("out/grm_$c")
done

# Figures: displacement, velocity and acceleration of P8 and P4 with the cases overlaid (the
# paper's Fig. 4; cases whose scales differ by more than 10x on separate axes), every joint,
# and 3D snapshots of each case (Fig. 3).
begin "GRM figures"
"$screwfem" plot "${run_dirs[@]}" -o out/figures --times 0,0.5,1,1.5,2
end "GRM figures"

# Actuator efforts of the rigid GRM across the drive switch at 0.5 s, with and without the
# restart at the switch and with full numerical damping (docs/numerics.md, "Efforts across drive
# switches"): out/figures/switch_efforts/effort_switch_<joint>.png and a table.
begin "GRM efforts across a switch"
mkdir -p out/figures/switch_efforts
/usr/bin/python3 tools/grm_switch_efforts.py "$screwfem" out/figures/switch_efforts \
  | tee out/figures/switch_efforts/table.md
end "GRM efforts across a switch"

# One self-contained browser viewer per case (three.js inlined; opens from file://).
begin "GRM viewers"
for c in "${cases[@]}"; do
  "$screwfem" view "out/grm_$c" -o "out/viewer/grm_$c.html"
done
end "GRM viewers"

# Python: the closed-loop soft arm (examples/python/soft_arm_control.py), a PID controller on
# the tip height setting a tendon's tension between steps, recorded with Simulation.record into
# out/soft_arm_control/ (the files `screwfem run` writes) and shown in a viewer page.
begin "Python: soft arm in closed loop"
PYTHONPATH=$build_dir/python /usr/bin/python3 examples/python/soft_arm_control.py \
  --out out/soft_arm_control --force
"$screwfem" view out/soft_arm_control -o out/viewer/soft_arm_control.html
end "Python: soft arm in closed loop"

echo
echo "Phase timings:"
printf '  %s\n' "${timings[@]}"
echo "Output written to out/statics.txt, out/grm_*/, out/soft_arm_control/, out/figures/ and"
echo "out/viewer/"
echo
echo "The program:  $build_dir/app/screwfem   (screwfem run SCENE.yaml -o DIR; plot DIR; view DIR)"
echo "The package:  PYTHONPATH=$build_dir/python /usr/bin/python3   (import screwfem)"
echo "Tutorials:    docs/tutorials/ (Jupyter notebooks); the Python API: docs/python.md"
