# Phase timing for the scripts (sourced, not run): `begin LABEL` ... `end LABEL` prints the
# phase's wall time and appends a line to the array `timings`; `now_us` is the time in
# microseconds. Uses bash's EPOCHREALTIME (no external tools).
now_us() { echo "${EPOCHREALTIME//[.,]/}"; }
timings=()
phase_start=0
begin() { echo "== $1"; phase_start=$(now_us); }
end() {
  local us=$(($(now_us) - phase_start)) t
  t=$(printf '%d.%01d s' $((us / 1000000)) $((us % 1000000 / 100000)))
  timings+=("$(printf '%-34s %10s' "$1" "$t")")
  echo "== $1: $t"
}
