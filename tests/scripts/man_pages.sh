#!/usr/bin/env bash
# The build writes a man page per subcommand (mbstorm-<sub>(1)) and mbstorm(1), from the
# binary's own --help: each exists for every subcommand `mbstorm --help` lists, reads under
# man(1) with its NAME, and mentions every option of `mbstorm <sub> --help`; mbstorm(1) lists
# every subcommand and points to each page.
set -euo pipefail
mbstorm=$1
build=$(cd "$(dirname "$mbstorm")" && pwd)
pages="$build/man/man1"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL $*" >&2; exit 1; }

if ! command -v help2man >/dev/null; then
  echo "help2man is not installed (scripts/setup.sh installs it): the build made no man pages" >&2
  exit 77
fi
[ -d "$pages" ] || fail "no $pages: build the mbstorm_man_pages target (part of the default build)"

# Renders a page as plain text, wide enough that no line breaks inside an option.
render() { MANWIDTH=200 man -l "$1" 2>"$work/man.err" | sed 's/\xe2\x80\x90/-/g'; }
# Every option name in a --help text: -x and --long-name words at the start of its lines.
options_in() { grep -E '^  -' | sed -E 's/^ +//; s/ .*//' | tr ',' '\n' | grep -E '^--?[A-Za-z]' | sort -u; }

"$mbstorm" --help >"$work/help"
mapfile -t subcommands < <(sed -n '/^Subcommands:/,$p' "$work/help" | sed -n 's/^  \([a-z][a-z-]*\) .*/\1/p')
[ ${#subcommands[@]} -ge 9 ] || fail "only ${#subcommands[@]} subcommands in mbstorm --help"

render "$pages/mbstorm.1.gz" >"$work/main" || fail "man -l mbstorm.1.gz: $(cat "$work/man.err")"
grep -q '^       mbstorm - Modbus TCP load tester' "$work/main" || fail "mbstorm(1) has no NAME line"
checked=0
for sub in "${subcommands[@]}"; do
  page="$pages/mbstorm-$sub.1.gz"
  [ -f "$page" ] || fail "no man page for '$sub' ($page)"
  grep -qE "^       $sub +[A-Za-z]" "$work/main" || fail "mbstorm(1) does not list '$sub'"
  grep -q "mbstorm-$sub(1)" "$work/main" || fail "mbstorm(1) does not point to mbstorm-$sub(1)"
  render "$page" >"$work/page" || fail "man -l $page: $(cat "$work/man.err")"
  [ ! -s "$work/man.err" ] || fail "man -l $page warns: $(cat "$work/man.err")"
  grep -q "^       mbstorm-$sub - " "$work/page" || fail "mbstorm-$sub(1) has no NAME line"
  grep -q "^       mbstorm $sub " "$work/page" || fail "mbstorm-$sub(1) has no synopsis 'mbstorm $sub ...'"
  grep -q "mbstorm(1)" "$work/page" || fail "mbstorm-$sub(1) does not point to mbstorm(1)"
  # The footer's Examples and Exit status are sections of their own, one line per example.
  grep -q "^EXAMPLES" "$work/page" || fail "mbstorm-$sub(1) has no EXAMPLES section"
  grep -q "^EXIT STATUS" "$work/page" || fail "mbstorm-$sub(1) has no EXIT STATUS section"
  grep -qE "^       mbstorm $sub( |$)" <(sed -n '/^EXAMPLES/,/^[A-Z]/p' "$work/page") ||
    fail "mbstorm-$sub(1)'s EXAMPLES do not start a line with 'mbstorm $sub'"
  "$mbstorm" "$sub" --help | options_in >"$work/options"
  [ -s "$work/options" ] || fail "no options found in mbstorm $sub --help"
  while read -r option; do
    grep -qE -- "(^|[ ,])$option([ ,=]|$)" "$work/page" || fail "mbstorm-$sub(1) does not mention $option"
    checked=$((checked + 1))
  done <"$work/options"
done
# No page for a subcommand that is not there any more.
for page in "$pages"/mbstorm-*.1.gz; do
  name=$(basename "$page" .1.gz)
  [[ " ${subcommands[*]} " == *" ${name#mbstorm-} "* ]] || fail "a page for no subcommand: $page"
done
echo "ok   ${#subcommands[@]} subcommand pages and mbstorm(1); $checked options, each on its page"
