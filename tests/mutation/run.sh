#!/usr/bin/env bash
# Applies each mutation in mutations.txt to a scratch copy of the tree (a git worktree of
# HEAD), builds the release preset there (incrementally after the first build), runs the
# suite named for it and reports whether a test caught it. Exit 1 when any survives.
#   bash tests/mutation/run.sh [SCRATCH_DIR]
# About 6 min for the first build on 2 cores, then a minute or two per mutation (12 mutants:
# 33 min on 2026-11-29 beside other builds, all caught).
set -uo pipefail
repo=$(cd "$(dirname "$0")/../.." && pwd)
scratch=${1:-$repo/build/mutation}
if [ ! -d "$scratch/.git" ] && [ ! -f "$scratch/.git" ]; then
  git -C "$repo" worktree add --detach "$scratch" HEAD >/dev/null || exit 2
fi
git -C "$scratch" checkout --detach -q "$(git -C "$repo" rev-parse HEAD)" || exit 2
cd "$scratch"
# The tests find the Modbus documents in ../shared beside the source tree.
[ -e "$scratch/../shared" ] || [ ! -d "$repo/../shared" ] || ln -s "$repo/../shared" "$scratch/../shared"
cmake --preset release >/dev/null || exit 2
cmake --build --preset release -j "$(nproc)" >/tmp/mutation-build.log 2>&1 || { echo "the tree does not build"; exit 2; }
# Every suite passes unmutated, or a failure would prove nothing.
suites=$(python3 -c 'import sys
for l in open(sys.argv[1]):
    if l.strip() and not l.startswith("#"): print(l.split(" | ", 3)[3].strip())' "$repo/tests/mutation/mutations.txt" | paste -sd'|')
ctest --preset release -R "$suites" -j 4 >/tmp/mutation-test.log 2>&1 ||
  { echo "the suites fail unmutated: see /tmp/mutation-test.log"; exit 2; }
survived=0 caught=0
while IFS= read -r line; do
  case "$line" in ''|'#'*) continue ;; esac
  # Fields split on " | " (a field may hold "||", never " | ").
  mapfile -t fields < <(python3 -c 'import sys; print("\n".join(f.strip() for f in sys.argv[1].split(" | ", 3)))' "$line")
  [ ${#fields[@]} -eq 4 ] || { echo "BAD LINE $line"; survived=$((survived + 1)); continue; }
  file=${fields[0]} from=${fields[1]} to=${fields[2]} suite=${fields[3]}
  if ! grep -qF -- "$from" "$file"; then
    echo "STALE  $file: '$from' is not in it (update mutations.txt)"; survived=$((survived + 1)); continue
  fi
  python3 - "$file" "$from" "$to" <<'PY'
import sys
path, old, new = sys.argv[1:4]
text = open(path).read()
open(path, "w").write(text.replace(old, new, 1))
PY
  if ! cmake --build --preset release -j "$(nproc)" >/tmp/mutation-build.log 2>&1; then
    echo "caught $file: '$to' does not build"; caught=$((caught + 1))
  elif ctest --preset release -R "$suite" -j 4 >/tmp/mutation-test.log 2>&1; then
    echo "SURVIVED $file: '$from' -> '$to' (suite $suite passes)"; survived=$((survived + 1))
  else
    echo "caught   $file: '$from' -> '$to' ($(grep -c 'Failed\|\*\*\*' /tmp/mutation-test.log) failing in $suite)"
    caught=$((caught + 1))
  fi
  git checkout -q -- "$file"
done <"$repo/tests/mutation/mutations.txt"
echo "mutations: $caught caught, $survived survived"
[ "$survived" -eq 0 ]
