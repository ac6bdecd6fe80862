#!/usr/bin/env bash
# The house rules a machine can check (docs/architecture.md, "Code layout" and "Commits"), a
# phase of the test command (scripts/run-tests.sh):
#   1. every C++ file of the repository is laid out as .clang-format says (clang-format 14,
#      Debian's clang-format package): the files that differ are listed with the command that
#      fixes them;
#   2. every commit after the rule came in (kFirstChecked below, exclusive) has a subject of at
#      most 72 characters, and every commit that is not a merge has a body after a blank line.
# Prints one line per rule and exits non-zero when one is broken. With --fix, formats the
# files in place instead of checking them.
set -uo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# The last commit before the rules: its history is left as it was.
readonly kFirstChecked=7ab858f

status=0
mapfile -t files < <(git ls-files '*.cpp' '*.h' '*.hpp' | grep -v '^tests/layering/upward/')
if [[ "${1:-}" == --fix ]]; then
  clang-format -i "${files[@]}"
  exit 0
fi

if ! command -v clang-format > /dev/null; then
  echo "lint: clang-format not found (apt-get install clang-format)" >&2
  exit 1
fi
bad=()
for f in "${files[@]}"; do
  clang-format --dry-run --Werror "$f" > /dev/null 2>&1 || bad+=("$f")
done
if [[ ${#bad[@]} -eq 0 ]]; then
  echo "lint: layout: ${#files[@]} C++ files as .clang-format says"
else
  echo "lint: layout: ${#bad[@]} of ${#files[@]} C++ files differ from .clang-format:"
  printf '  %s\n' "${bad[@]}"
  echo "  fix: bash scripts/lint.sh --fix (or clang-format -i FILE)"
  status=1
fi

if ! git rev-parse -q --verify "$kFirstChecked^{commit}" > /dev/null; then
  echo "lint: commits: $kFirstChecked not in this clone's history (shallow?); not checked"
else
  long=$(git log --no-merges --format='%h %s' "$kFirstChecked..HEAD" | awk 'length($0) - 8 > 72')
  long_merges=$(git log --merges --format='%h %s' "$kFirstChecked..HEAD" |
    awk 'length($0) - 8 > 72')
  bodiless=$(git log --no-merges --format='%h %b%x00' "$kFirstChecked..HEAD" |
    tr -d '\n' | tr '\0' '\n' | awk 'NF == 1')
  count=$(git rev-list --count "$kFirstChecked..HEAD")
  if [[ -z "$long$long_merges$bodiless" ]]; then
    echo "lint: commits: $count after $kFirstChecked, subjects <= 72 characters with a body"
  else
    [[ -z "$long$long_merges" ]] || printf 'lint: subject over 72 characters: %s\n' $'\n'"$long$long_merges"
    [[ -z "$bodiless" ]] || printf 'lint: commit without a body: %s\n' $'\n'"$bodiless"
    status=1
  fi
fi
exit $status
