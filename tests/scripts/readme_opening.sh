#!/usr/bin/env bash
# The README opens with what mbstorm is (two lines), a sample of its console output that the
# current binary really prints (each sample line, numbers aside, is a line of a real run with
# the sample's flags), and then the two commands, the second being what CI (.ci/run) runs.
set -euo pipefail
mbstorm=$1
root=$(cd "$2/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
readme="$root/README.md"
fail() { echo "FAIL $*" >&2; exit 1; }

# Blocks in order: title, a two-line paragraph, the ```text sample, then the ```sh commands.
[ "$(sed -n 1p "$readme")" = "# mbstorm" ] || fail "README does not start with '# mbstorm'"
[ -z "$(sed -n 2p "$readme")" ] && [ -n "$(sed -n 3p "$readme")" ] && [ -n "$(sed -n 4p "$readme")" ] &&
  [ -z "$(sed -n 5p "$readme")" ] || fail "README line 3-4 is not a two-line description"
[ "$(sed -n 6p "$readme")" = '```text' ] || fail "README line 6 does not open the output sample"
sample_end=$(awk 'NR > 6 && /^```$/ {print NR; exit}' "$readme")
sed -n "7,$((sample_end - 1))p" "$readme" >"$work/sample"
commands_start=$(awk -v s="$sample_end" 'NR > s && /^```sh$/ {print NR; exit}' "$readme")
[ -n "$commands_start" ] && [ -z "$(sed -n "$((sample_end + 1)),$((commands_start - 1))p" "$readme" | grep -v '^$' | grep -v '^(')" ] ||
  fail "README: the two commands do not follow the sample"
sed -n "$((commands_start + 1)),$((commands_start + 2))p" "$readme" >"$work/commands"
grep -qx 'bash scripts/setup.sh && cmake --preset release && cmake --build --preset release && build/release/mbstorm run' "$work/commands" ||
  fail "README's first command is not the build-and-run command"
ci=$(grep -x 'bash scripts/setup.sh && bash scripts/test-all.sh' "$root/.ci/run")
[ "$(sed -n 2p "$work/commands")" = "$ci" ] || fail "README's second command is not what .ci/run runs"

# The sample: "$ mbstorm run ARGS", then output lines.
read -r prompt program args <"$work/sample"
[ "$prompt $program" = '$ mbstorm' ] || fail "the sample does not start with '\$ mbstorm ...'"
# shellcheck disable=SC2086
"$mbstorm" $args >"$work/real" 2>/dev/null || fail "mbstorm $args failed"
# Numbers with their units and separators become N; runs of spaces become one.
normalise() { sed -E 's/[0-9][0-9.,:]*([kMG]|µs|ms|ns|s|%|Z|T[0-9:]*Z)?/N/g; s/ +/ /g; s/ $//'; }
normalise <"$work/real" >"$work/real.n"
tail -n +2 "$work/sample" | normalise | while IFS= read -r line; do
  [ -z "$line" ] || grep -qxF -- "$line" "$work/real.n" || fail "sample line '$line' is not what mbstorm $args prints"
done
echo "ok   README opening: description, a sample that matches 'mbstorm $args', the two commands"
