#!/usr/bin/env bash
# A fuzz campaign outside the test command: the libFuzzer targets of tests/fuzz (parse, build,
# run) for a given time or number of executions each, at low priority, with a corpus that
# persists between campaigns (build/asan/fuzz-campaign/NAME/corpus). Needs the sanitizer tree
# of the test command (scripts/run-tests.sh, or cmake with scripts/sanitizer-config.sh's
# arguments and ninja -C build/asan screwfem_fuzz_parse screwfem_fuzz_build screwfem_fuzz_run).
#
#   scripts/fuzz-campaign.sh [-t SECONDS] [-r RUNS] [-j SLOTS] [-n NICE] [-s] [TARGET...]
#
#   -t SECONDS  wall time per target (default 600); with -r, whichever ends first
#   -r RUNS     executions per target (libFuzzer -runs; default: no limit)
#   -j SLOTS    targets run at once (default 2, one per core)
#   -n NICE     niceness of the fuzzers (default 10, so that builds beside it are not starved)
#   -s          print the counts of the last campaign again, run nothing
#   TARGET      parse, build, run (default: all three)
#
# Each target runs in libFuzzer's fork mode with one worker (-fork=1): a crash, sanitizer
# report, leak, timeout (10 s per input) or out-of-memory (1024 MB) is counted and kept
# (build/asan/fuzz-campaign/NAME/artifacts/) and the campaign goes on. At the end it prints,
# per target: executions, executions per second, crashes, timeouts, out-of-memory inputs, and
# the coverage (edges, features, corpus files) at the start and at the end; the new coverage is
# their difference. Exits non-zero when any target found a crash, timeout or out-of-memory;
# replay an artifact with build/asan/tests/fuzz/screwfem_fuzz_NAME FILE and, once the defect is
# fixed, commit the file to tests/fuzz/regressions/NAME/.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

seconds=600
runs=-1
slots=2
niceness=10
summary_only=0
while getopts "t:r:j:n:s" opt; do
  case $opt in
    t) seconds=$OPTARG ;;
    r) runs=$OPTARG ;;
    j) slots=$OPTARG ;;
    n) niceness=$OPTARG ;;
    s) summary_only=1 ;;
    *)
      sed -n '2,24p' "$0" >&2
      exit 2
      ;;
  esac
done
shift $((OPTIND - 1))
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(parse build run)

asan_dir=build/asan
source scripts/sanitizer-config.sh
export ASAN_OPTIONS UBSAN_OPTIONS
for name in "${targets[@]}"; do
  if [[ ! -x "$asan_dir/tests/fuzz/screwfem_fuzz_$name" ]]; then
    echo "fuzz-campaign: $asan_dir/tests/fuzz/screwfem_fuzz_$name is not built" >&2
    exit 2
  fi
done

# campaign NAME: the coverage of the corpus as it stands (one pass, -runs=0: the INITED line of
# DIR/start.txt), the campaign proper (DIR/log.txt), and the coverage of the corpus it leaves
# (DIR/end.txt; fork mode's own 'cov' counts differently).
campaign() {
  local name=$1 work=$asan_dir/fuzz-campaign/$1 seeds=() fuzzer=$asan_dir/tests/fuzz/screwfem_fuzz_$1
  mkdir -p "$work/corpus" "$work/artifacts"
  [[ -d "tests/fuzz/seeds/$name" ]] && seeds+=("tests/fuzz/seeds/$name")
  local corpora=("$work/corpus" examples/*/ tests/data "${seeds[@]}" "tests/fuzz/regressions/$name")
  local limits=(-timeout=10 -rss_limit_mb=1024 -max_len=65536)
  nice -n "$niceness" "$fuzzer" "${corpora[@]}" "${limits[@]}" -runs=0 > "$work/start.txt" 2>&1
  nice -n "$niceness" "$fuzzer" "${corpora[@]}" "${limits[@]}" -fork=1 -ignore_crashes=1 \
    -ignore_timeouts=1 -ignore_ooms=1 -max_total_time="$seconds" -runs="$runs" \
    -artifact_prefix="$work/artifacts/" > "$work/log.txt" 2>&1
  echo $? > "$work/status"
  nice -n "$niceness" "$fuzzer" "${corpora[@]}" "${limits[@]}" -runs=0 > "$work/end.txt" 2>&1
}

start=$(date +%s)
running=0
[[ $summary_only -eq 1 ]] && targets_to_run=() || targets_to_run=("${targets[@]}")
for name in "${targets_to_run[@]}"; do
  if [[ $running -ge $slots ]]; then
    wait -n
    running=$((running - 1))
  fi
  echo "fuzz-campaign: $name for at most ${seconds} s$([[ $runs -ge 0 ]] && echo ", $runs runs")"
  campaign "$name" &
  running=$((running + 1))
done
wait

# Fork mode prints '#RUNS: cov: C ft: F corp: N exec/s E oom/timeout/crash: O/T/X time: S ...'
# after every job (executions, speed and failures come from its last line); the corpus passes
# before and after it 'INITED cov: C ft: F corp: N/SIZE ...' (the coverage: edges, features
# and inputs).
# inited LOG: edges, features and inputs of its INITED line.
inited() {
  grep -m1 -E 'INITED cov:' "$1" |
    sed -E 's/.*INITED cov: ([0-9]+) ft: ([0-9]+) corp: ([0-9]+).*/\1 \2 \3/'
}
status=0
printf '%-6s %10s %8s %8s %8s %6s  %-22s %-22s\n' target executions exec/s crashes timeouts \
  ooms "start cov/ft/corp" "end cov/ft/corp"
for name in "${targets[@]}"; do
  work=$asan_dir/fuzz-campaign/$name
  log=$work/log.txt
  last=$(grep -E '^#[0-9]+: cov:' "$log" | tail -n 1)
  read -r execs eps counts <<< "$(sed -E \
    's/^#([0-9]+): cov: .* exec\/s:? ([0-9]+) oom\/timeout\/crash: ([0-9\/]+).*/\1 \2 \3/' \
    <<< "$last")"
  read -r cov0 ft0 corp0 <<< "$(inited "$work/start.txt")"
  read -r cov ft corp <<< "$(inited "$work/end.txt")"
  IFS=/ read -r ooms timeouts crashes <<< "${counts:-0/0/0}"
  printf '%-6s %10s %8s %8s %8s %6s  %-22s %-22s\n' "$name" "${execs:-0}" "${eps:-0}" \
    "${crashes:-0}" "${timeouts:-0}" "${ooms:-0}" "${cov0:-?}/${ft0:-?}/${corp0:-?}" \
    "${cov:-?}/${ft:-?}/${corp:-?}"
  if [[ -z "$last" ]]; then
    echo "  $name: no statistics in $log (exit status $(cat "$work/status" 2> /dev/null))"
    tail -n 20 "$log"
    status=1
  elif [[ "${crashes:-0}" != 0 || "${timeouts:-0}" != 0 || "${ooms:-0}" != 0 ]]; then
    ls "$work/artifacts" | sed "s|^|  $name artifact: $work/artifacts/|"
    status=1
  fi
done
echo "fuzz-campaign: $(($(date +%s) - start)) s wall"
exit $status
