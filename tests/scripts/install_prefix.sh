#!/usr/bin/env bash
# `cmake --install <build> --prefix X` puts a working mbstorm in X/bin, its documentation in
# X/share/doc/mbstorm, its man pages in X/share/man/man1, its bash completion in
# X/share/bash-completion/completions, its example scenarios in X/share/mbstorm/scenarios and
# the coverage runtime in X/share/mbstorm/coverage.
set -euo pipefail
build=$(cd "$(dirname "$1")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cmake --install "$build" --prefix "$work/prefix" >"$work/install.log"
[ -x "$work/prefix/bin/mbstorm" ] || { echo "FAIL no $work/prefix/bin/mbstorm after cmake --install:" >&2; cat "$work/install.log" >&2; exit 1; }
# Whole outputs first, then the checks: `mbstorm ... | grep -q` fails under pipefail when grep
# exits before a slower (sanitizer) build has written everything (SIGPIPE).
version_text=$("$work/prefix/bin/mbstorm" --version)
version=${version_text%%$'\n'*}
[[ "$version" == "mbstorm "[0-9]* ]] || { echo "FAIL installed mbstorm --version printed '$version'" >&2; exit 1; }
run_help=$("$work/prefix/bin/mbstorm" run --help)
grep -q -- '--target' <<<"$run_help" || { echo "FAIL installed mbstorm run --help" >&2; exit 1; }
for f in doc/mbstorm/README.md doc/mbstorm/copyright doc/mbstorm/docs/json-schema.md mbstorm/scenarios/ci-gate.yaml man/man1/mbstorm.1.gz man/man1/mbstorm-run.1.gz mbstorm/coverage/mbstorm_coverage.c \
  bash-completion/completions/mbstorm; do
  [ -f "$work/prefix/share/$f" ] || { echo "FAIL share/$f not installed" >&2; exit 1; }
done
# The installed binary names its own scenarios and finds one by name (not the checkout's).
grep -q -- "$work/prefix/share/mbstorm/scenarios" <<<"$run_help" ||
  { echo "FAIL installed mbstorm run --help does not name $work/prefix/share/mbstorm/scenarios" >&2; exit 1; }
by_name=$(cd "$work" && "$work/prefix/bin/mbstorm" run ci-gate --print-scenario)
grep -q -- "from $work/prefix/share/mbstorm/scenarios/ci-gate.yaml" <<<"$by_name" ||
  { echo "FAIL installed mbstorm run ci-gate did not find the installed scenario: $(head -1 <<<"$by_name")" >&2; exit 1; }
echo "ok   installed: $version, its docs and scenarios (run NAME finds them)"
