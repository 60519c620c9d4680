#!/usr/bin/env bash
# Builds the .deb from build/release (no rebuild: cpack over what is built), installs it with
# apt-get (so its dependencies resolve), tries the installed copy (/usr/bin/mbstorm --version,
# a 1-second load test against the embedded slave, a packaged scenario, the man pages and the
# bash completion), then removes it and any package it pulled in: the machine is left as it
# was. Needs root. Run by scripts/test-all.sh after the release tests.
#   bash scripts/deb-check.sh [BUILD_DIR]     (default build/release)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build/release}
fail() { echo "deb-check: FAIL $*" >&2; exit 1; }

[ -x "$build/mbstorm" ] && [ -f "$build/CPackConfig.cmake" ] || fail "no built $build (cmake --build --preset release first)"
[ "$EUID" -eq 0 ] || fail "needs root: it installs and removes a package"
if dpkg-query -W -f='${Status}' mbstorm 2>/dev/null | grep -q "installed"; then
  fail "a mbstorm package is installed already; this check installs and removes its own"
fi
[ ! -e /usr/bin/mbstorm ] || fail "/usr/bin/mbstorm exists and is not from a package: not overwriting it"

work=$(mktemp -d)
dpkg-query -W -f='${binary:Package}\n' | sort >"$work/before"
cleanup() {
  if dpkg-query -W -f='${Status}' mbstorm 2>/dev/null | grep -q "installed"; then
    dpkg -r mbstorm >/dev/null || echo "deb-check: could not remove mbstorm" >&2
  fi
  # Whatever the install pulled in goes too.
  dpkg-query -W -f='${binary:Package}\n' | sort >"$work/after"
  mapfile -t added < <(comm -13 "$work/before" "$work/after")
  if [ ${#added[@]} -ne 0 ]; then
    dpkg -r "${added[@]}" >/dev/null || echo "deb-check: could not remove ${added[*]}" >&2
  fi
  rm -rf "$work"
}
trap cleanup EXIT

start=$SECONDS
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work/out" >"$work/cpack.log" 2>&1 ||
  fail "cpack failed:"$'\n'"$(cat "$work/cpack.log")"
deb=$(echo "$work"/out/mbstorm_*.deb)
[ -f "$deb" ] || fail "cpack made no mbstorm_*.deb"
echo "deb-check: built $(basename "$deb") ($(stat -c %s "$deb") bytes) in $((SECONDS - start))s"

start=$SECONDS
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$deb" \
  >"$work/apt.log" 2>&1 || fail "apt-get install failed:"$'\n'"$(cat "$work/apt.log")"
echo "deb-check: installed in $((SECONDS - start))s"

installed=/usr/bin/mbstorm  # the package's copy (a variable: it is no program the tests need)
[ "$(type -P mbstorm)" = "$installed" ] || fail "mbstorm on PATH is $(type -P mbstorm), not /usr/bin/mbstorm"
"$installed" --version >"$work/version" || fail "$installed --version exited $?"
version=$(dpkg-deb -f "$deb" Version)
[ "$(head -n 1 "$work/version")" = "mbstorm $version" ] || fail "installed --version: $(cat "$work/version")"
sed 's/^/deb-check:   /' "$work/version"

timeout 60 "$installed" run -d 1s -c 2 >"$work/run" 2>&1 || fail "mbstorm run -d 1s exited $?:"$'\n'"$(cat "$work/run")"
grep -q "0x03 read_holding_registers" "$work/run" || fail "the 1-second run reported no transactions:"$'\n'"$(cat "$work/run")"
"$installed" run --print-scenario /usr/share/mbstorm/scenarios/quickstart.yaml >/dev/null ||
  fail "the packaged scenario quickstart.yaml does not load"

for page in mbstorm mbstorm-run mbstorm-serve; do
  [ "$(man -w "$page")" = "/usr/share/man/man1/$page.1.gz" ] || fail "man -w $page: $(man -w "$page" 2>&1)"
done
loaded=$(bash -c 'source /usr/share/bash-completion/bash_completion && __load_completion mbstorm && complete -p mbstorm')
[[ "$loaded" == *"-F _mbstorm mbstorm"* ]] || fail "bash-completion does not load the installed completion: $loaded"
[ -f /usr/share/doc/mbstorm/copyright ] || fail "no /usr/share/doc/mbstorm/copyright"

dpkg -r mbstorm >/dev/null || fail "dpkg -r mbstorm failed"
[ ! -e /usr/bin/mbstorm ] && [ ! -e /usr/share/man/man1/mbstorm.1.gz ] &&
  [ ! -e /usr/share/bash-completion/completions/mbstorm ] || fail "files left after dpkg -r mbstorm"
echo "deb-check: ok: installed, ran 1 s of load, found the man pages and completion, removed"
