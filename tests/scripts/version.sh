#!/usr/bin/env bash
# `mbstorm --version` names the version (CMake's project(VERSION), written nowhere else), the
# git commit built, the compiler, the build type, this kernel's io_uring features and the backend
# run and serve would use (epoll, and why, where io_uring is refused); the
# commit is "unknown" outside a git checkout of mbstorm (cmake/build_info.cmake run on a plain
# folder and on a folder inside another repository).
set -euo pipefail
mbstorm=$1
root=$(cd "$2/../.." && pwd)
build=$(cd "$(dirname "$mbstorm")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL $*" >&2; exit 1; }

"$mbstorm" --version >"$work/out" || fail "mbstorm --version exited $?"
mapfile -t lines <"$work/out"
[ ${#lines[@]} -eq 6 ] || fail "--version printed ${#lines[@]} lines, not 6:$(printf '\n  %s' "${lines[@]}")"

version=$(sed -n 's/^project(mbstorm VERSION \([0-9.]*\) .*/\1/p' "$root/CMakeLists.txt")
[ -n "$version" ] || fail "no project(mbstorm VERSION ...) in CMakeLists.txt"
[ "${lines[0]}" = "mbstorm $version" ] || fail "first line '${lines[0]}', expected 'mbstorm $version'"
if grep -rnF "\"$version\"" "$root/src" >"$work/literal"; then
  fail "a second literal of the version in src/:"$'\n'"$(cat "$work/literal")"
fi

commit=${lines[1]#commit: }
[ "$commit" != "${lines[1]}" ] || fail "second line '${lines[1]}' is not 'commit: ...'"
if git -C "$root" rev-parse --git-dir >/dev/null 2>&1; then
  expected=$(git -C "$root" describe --always)
  # -dirty depends on the files at build time, the commit itself must match.
  [ "${commit%-dirty}" = "$expected" ] || fail "commit '$commit', git describe says '$expected'"
fi

compiler_line='^compiler: (GNU|Clang) [0-9]+\.[0-9]+'
[[ "${lines[2]}" =~ $compiler_line ]] || fail "third line '${lines[2]}'"
build_type=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$build/CMakeCache.txt")
[ "${lines[3]}" = "build type: $build_type" ] || fail "fourth line '${lines[3]}', build type is '$build_type'"

io=${lines[4]}
prefix="io_uring (kernel $(uname -r)):"
[ "${io#"$prefix"}" != "$io" ] || fail "fifth line '$io' does not start with '$prefix'"
known=" multishot_accept multishot_recv buf_ring send_zc direct_descriptors single_issuer defer_taskrun coop_taskrun "
if [ "$io" != "$prefix unavailable (kernel too old, or io_uring blocked)" ]; then
  names=${io#"$prefix"}
  names=${names/; not offered:/}
  count=0
  for name in $names; do
    [[ "$known" == *" $name "* ]] || fail "unknown io_uring feature '$name' in '$io'"
    count=$((count + 1))
  done
  [ "$count" -eq 8 ] || fail "'$io' names $count features, not each of the 8 once"
  [ "${lines[5]}" = "backend: io_uring" ] || fail "sixth line '${lines[5]}', io_uring is here"
else
  [[ "${lines[5]}" == "backend: epoll ("*")" ]] || fail "sixth line '${lines[5]}' names no reason for epoll"
fi

# The commit outside a checkout: a plain folder, and a folder inside another repository.
generate() {
  cmake -DSOURCE_DIR="$1" -DOUTPUT="$work/info.cpp" -DVERSION=9.9.9 -DCOMPILER="GNU 1.0" \
    -DBUILD_TYPE=Release -P "$root/cmake/build_info.cmake"
  grep -o '"9.9.9", "[^"]*"' "$work/info.cpp" | sed 's/.*, "//; s/"$//'
}
mkdir -p "$work/plain" "$work/other/src"
[ "$(generate "$work/plain")" = unknown ] || fail "outside a checkout the commit is '$(generate "$work/plain")'"
git -C "$work/other" init -q
git -C "$work/other" -c user.name=t -c user.email=t@t commit -q --allow-empty -m x
[ "$(generate "$work/other/src")" = unknown ] || fail "inside another repository the commit is '$(generate "$work/other/src")'"
if git -C "$root" rev-parse --git-dir >/dev/null 2>&1; then
  [ "$(generate "$root")" = "$(git -C "$root" describe --always --dirty)" ] || fail "in the checkout the commit is '$(generate "$root")'"
fi
echo "ok   ${lines[0]}, ${lines[1]}, ${lines[4]}"
