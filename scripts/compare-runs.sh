#!/usr/bin/env bash
# Runs every example scene (examples/**/*.yaml, tests/data/*.yaml) with two screwfem programs
# and compares what they write, byte for byte: the check that a refactoring changed no double.
#   bash scripts/compare-runs.sh OLD_PROGRAM NEW_PROGRAM [OUTDIR]
# OLD_PROGRAM and NEW_PROGRAM are two builds' app/screwfem (e.g. a worktree of the revision
# before the change). Tables, JSON and VTK files are compared whole, except the wall-clock
# fields of summary.json (wall_time, steps_per_second, real_time_factor and the like), which
# are dropped before comparing, and the output lock .screwfem.lock (it holds the run's process
# id). Prints one line per scene and exits non-zero when any output differs or a run's exit
# status differs.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if [[ $# -lt 2 ]]; then
  echo "usage: compare-runs.sh OLD_PROGRAM NEW_PROGRAM [OUTDIR]" >&2
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
out=${3:-$(mktemp -d)}
mkdir -p "$out"

# summary.json without the fields that measure the machine rather than the run.
strip_clock() {
  /usr/bin/python3 - "$1" << 'EOF'
import json, sys
with open(sys.argv[1]) as f:
    s = json.load(f)
def drop(o):
    if isinstance(o, dict):
        return {k: drop(v) for k, v in o.items()
                if not any(w in k for w in ("wall", "per_second", "seconds_", "cpu", "elapsed",
                                          "real_time"))}
    if isinstance(o, list):
        return [drop(v) for v in o]
    return o
print(json.dumps(drop(s), sort_keys=True, indent=1))
EOF
}

differ=0
scenes=$(find examples tests/data -name '*.yaml' | sort)
for scene in $scenes; do
  name=$(echo "${scene%.yaml}" | tr '/' '_')
  "$old" run "$scene" -o "$out/old/$name" --quiet --force > "$out/$name.old.log" 2>&1
  s_old=$?
  "$new" run "$scene" -o "$out/new/$name" --quiet --force > "$out/$name.new.log" 2>&1
  s_new=$?
  status="same"
  if [[ $s_old -ne $s_new ]]; then
    status="exit status $s_old -> $s_new"
  else
    while IFS= read -r f; do
      rel=${f#"$out/old/$name/"}
      [[ "$rel" == .screwfem.lock ]] && continue  # the run's process id (io/run.h)
      g="$out/new/$name/$rel"
      if [[ ! -e "$g" ]]; then
        status="missing $rel"
        break
      fi
      if [[ "$rel" == summary.json ]]; then
        cmp -s <(strip_clock "$f") <(strip_clock "$g") || { status="differs: $rel"; break; }
      elif ! cmp -s "$f" "$g"; then
        status="differs: $rel"
        break
      fi
    done < <(find "$out/old/$name" -type f | sort)
  fi
  [[ "$status" == same ]] || differ=1
  printf '%-50s exit %d  %s\n' "$scene" "$s_old" "$status"
done
exit $differ
