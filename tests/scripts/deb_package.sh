#!/usr/bin/env bash
# `cpack -G DEB` in the build folder makes mbstorm_<version>_<arch>.deb: the stripped binary as
# the only program, its library dependencies from dpkg-shlibdeps, the scenarios under
# /usr/share/mbstorm, the docs and a copyright file under /usr/share/doc/mbstorm, the man
# pages and the bash and zsh completions; everything owned by root, nothing under /usr/local. The
# package is built into a temporary folder and unpacked, not installed (scripts/deb-check.sh
# installs it).
set -euo pipefail
build=$(cd "$(dirname "$1")" && pwd)
root=$(cd "$2/../.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL $*" >&2; exit 1; }

command -v dpkg-shlibdeps >/dev/null || fail "dpkg-shlibdeps is missing (dpkg-dev; scripts/setup.sh installs it)"
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work/out" >"$work/cpack.log" 2>&1 ||
  fail "cpack failed:"$'\n'"$(cat "$work/cpack.log")"
version=$(sed -n 's/^project(mbstorm VERSION \([0-9.]*\) .*/\1/p' "$root/CMakeLists.txt")
deb="$work/out/mbstorm_${version}_$(dpkg --print-architecture).deb"
[ -f "$deb" ] || fail "no $(basename "$deb"); cpack made: $(cd "$work/out" && echo *.deb)"

field() { dpkg-deb -f "$deb" "$1"; }
[ "$(field Package)" = mbstorm ] || fail "Package: $(field Package)"
[ "$(field Version)" = "$version" ] || fail "Version: $(field Version), project version $version"
depends=$(field Depends)
for library in libc6 libstdc++6 liburing2 libfmt9 libyaml-cpp0.7 zlib1g; do
  [[ ", $depends," == *", $library "* ]] || fail "Depends lacks $library: $depends"
done
[ -n "$(field Maintainer)" ] && [ -n "$(field Description)" ] || fail "no Maintainer or Description"

dpkg-deb -c "$deb" >"$work/list"
awk '$2 != "root/root" {print}' "$work/list" >"$work/owners"
[ ! -s "$work/owners" ] || fail "files not owned by root:"$'\n'"$(cat "$work/owners")"
grep -q '\./usr/local' "$work/list" && fail "files under /usr/local"
awk '$1 ~ /^-..x/ {print $NF}' "$work/list" >"$work/programs"
[ "$(cat "$work/programs")" = ./usr/bin/mbstorm ] || fail "programs other than /usr/bin/mbstorm:"$'\n'"$(cat "$work/programs")"
awk '($1 ~ /^d/ && $1 != "drwxr-xr-x") || ($1 ~ /^-/ && $1 != "-rw-r--r--" && $1 != "-rwxr-xr-x") {print}' "$work/list" >"$work/modes"
[ ! -s "$work/modes" ] || fail "unusual permissions:"$'\n'"$(cat "$work/modes")"

dpkg-deb -x "$deb" "$work/root"
for f in usr/share/doc/mbstorm/copyright usr/share/doc/mbstorm/README.md usr/share/doc/mbstorm/docs/json-schema.md \
  usr/share/mbstorm/scenarios/ci-gate.yaml usr/share/mbstorm/scenarios/devices/example-device.yaml \
  usr/share/bash-completion/completions/mbstorm usr/share/zsh/vendor-completions/_mbstorm; do
  [ -f "$work/root/$f" ] || fail "/$f is not in the package"
done
for page in "$build"/man/man1/*.1.gz; do
  [ -f "$work/root/usr/share/man/man1/$(basename "$page")" ] || fail "man page $(basename "$page") is not in the package"
done
[ -f "$work/root/usr/share/man/man1/mbstorm-run.1.gz" ] || fail "no man pages in the package"
readelf -S --wide "$work/root/usr/bin/mbstorm" >"$work/sections"
grep -qE '\.(debug_info|symtab) ' "$work/sections" && fail "/usr/bin/mbstorm is not stripped"
first=$("$work/root/usr/bin/mbstorm" --version)  # whole, then its first line: no SIGPIPE
first=${first%%$'\n'*}
[ "$first" = "mbstorm $version" ] || fail "the packaged mbstorm --version says '$first'"
echo "ok   $(basename "$deb"): $(wc -l <"$work/list") entries, $(stat -c %s "$deb") bytes, Depends: $depends"
