#!/usr/bin/env bash
# The image of deploy/kubernetes/Containerfile (issue #32), built with podman from this build's
# .deb and run as a "restricted" pod runs it (the image's non-root user, every capability
# dropped, no new privileges, no network but loopback): `mbstorm --version` and a 1-second
# `mbstorm run` against `mbstorm serve` in one container, under Podman's default seccomp profile,
# Docker's (deploy/seccomp/mbstorm-io_uring.json without the three io_uring calls) and the
# shipped mbstorm-io_uring.json. With the shipped profile both use io_uring; under the defaults
# --version says io_uring is blocked and serve and run run on the portable epoll backend.
# The base is debian:12-slim when podman has it or can pull it, else a Debian 12 made here by
# debootstrap from Debian's mirror (kept as localhost/mbstorm-test-base:bookworm for the next
# run); the Containerfile's apt-get needs that mirror either way. podman runs rootful with runc
# (Debian 12's crun refuses hybrid cgroup hierarchies), the build on the host's network (no
# container network plugins needed) and the containers with limits on open files and processes
# that a sandbox can grant (podman's defaults are higher).
# Skips (exit 77) when podman cannot run a container on this machine at all.
#   bash container_image.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
root=$(cd "$2/../.." && pwd)
build=$(cd "$(dirname "$mbstorm")" && pwd)
work=$(mktemp -d)
image=localhost/mbstorm-test:$$
cleanup() {
  podman rmi -f "$image" >/dev/null 2>&1
  rm -rf "$work"
}
trap cleanup EXIT
fail=0
cannot() { echo "skip: podman cannot run a container here: $*"; exit 77; }

command -v podman >/dev/null ||
  { echo "skip: podman is not installed (scripts/setup.sh installs it)"; exit 77; }
[ "$(id -u)" = 0 ] || cannot "not root (this test runs rootful podman)"
# Limits a sandbox can grant: podman asks for more open files than a hard limit may allow, and
# conmon, which starts the container, may itself hold fewer processes than this shell.
nofile=$(ulimit -Hn)
[ "$nofile" = unlimited ] || [ "$nofile" -gt 65536 ] && nofile=65536
podman=(podman --runtime runc)
limits=(--ulimit "nofile=$nofile:$nofile" --ulimit "nproc=4096:4096")
# Everything a restricted pod gets, but the seccomp profile (each run names its own).
restricted=(--rm --network none --cap-drop ALL --security-opt no-new-privileges "${limits[@]}")

# The base: debian:12-slim, or Debian 12 by debootstrap.
base=docker.io/library/debian:12-slim
if ! podman image exists "$base" && ! timeout 120 podman pull -q "$base" >"$work/pull.log" 2>&1; then
  base=localhost/mbstorm-test-base:bookworm
  if ! podman image exists "$base"; then
    command -v debootstrap >/dev/null ||
      { echo "skip: debootstrap is not installed (scripts/setup.sh installs it)"; exit 77; }
    if ! debootstrap --variant=minbase bookworm "$work/rootfs" http://deb.debian.org/debian \
      >"$work/debootstrap.log" 2>&1; then
      echo "skip: no debian:12-slim ($(tail -1 "$work/pull.log")) and debootstrap cannot reach" \
        "Debian's mirror: $(tail -1 "$work/debootstrap.log")"
      exit 77
    fi
    tar -C "$work/rootfs" -c . | podman import -q - "$base" >/dev/null ||
      { echo "FAIL podman import"; exit 1; }
  fi
fi
"${podman[@]}" run --rm --network none "${limits[@]}" "$base" true >"$work/probe.log" 2>&1 ||
  cannot "$(tail -1 "$work/probe.log")"
echo "ok   base image $base runs"

# The image, from this build's package, as README.md's "Running on Kubernetes" builds it.
mkdir -p "$work/context"
cpack -G DEB --config "$build/CPackConfig.cmake" -B "$work/deb" >"$work/cpack.log" 2>&1 ||
  { echo "FAIL cpack:"; tail -20 "$work/cpack.log"; exit 1; }
cp "$work"/deb/mbstorm_*.deb "$work/context/"
if ! podman build --runtime runc --network host "${limits[@]}" --layers=false --from "$base" \
  -f "$root/deploy/kubernetes/Containerfile" -t "$image" "$work/context" >"$work/build.log" 2>&1; then
  echo "FAIL podman build:"; tail -20 "$work/build.log"; exit 1
fi
echo "ok   image built from $(basename "$work"/context/mbstorm_*.deb) on $base"
user=$("${podman[@]}" run "${restricted[@]}" "$image" id -u 2>&1)
[ "$user" = 10001 ] && echo "ok   runs as uid 10001" || { echo "FAIL runs as '$user', not uid 10001"; fail=1; }

# Docker's default profile: the shipped one without the three io_uring calls.
/usr/bin/python3 - "$root/deploy/seccomp/mbstorm-io_uring.json" "$work/docker-default.json" <<'PY'
import json, sys
profile = json.load(open(sys.argv[1]))
for entry in profile["syscalls"]:
    entry["names"] = [n for n in entry["names"] if not n.startswith("io_uring_")]
profile["syscalls"] = [e for e in profile["syscalls"] if e["names"]]
json.dump(profile, open(sys.argv[2], "w"))
PY
# serve in the background, run against it once it listens; run's exit code.
serve_then_run=': >/tmp/serve.log
mbstorm serve --listen 127.0.0.1:1502 -d 30s >/tmp/serve.log 2>&1 &
i=0
until grep -q "listening on" /tmp/serve.log || [ $i -ge 100 ] || ! kill -0 $! 2>/dev/null; do
  sleep 0.1; i=$((i + 1))
done
cat /tmp/serve.log
mbstorm run -d 1s --target 127.0.0.1:1502'

# check NAME WANT-EXIT PATTERN...: the last podman run's exit and lines (grep -E) it printed.
check() {
  local name=$1 want=$2 pattern missing=(); shift 2
  for pattern in "$@"; do grep -qE -- "$pattern" "$work/out" || missing+=("$pattern"); done
  if [ "$rc" = "$want" ] && [ ${#missing[@]} -eq 0 ]; then echo "ok   $name: exit $rc"; return; fi
  echo "FAIL $name: exit $rc (want $want), missing: ${missing[*]}"
  sed 's/^/  /' "$work/out" | head -30
  fail=1
}
in_container() {
  local seccomp=$1; shift
  "${podman[@]}" run "${restricted[@]}" ${seccomp:+--security-opt "seccomp=$seccomp"} "$image" "$@" >"$work/out" 2>&1
  rc=$?
}
features="^io_uring \(kernel .*\): [a-z_ ]*multishot_accept"
blocked="^io_uring \(kernel .*\): unavailable \(kernel too old, or io_uring blocked\)"
for profile in podman-default docker-default shipped; do
  case $profile in
    podman-default) seccomp= ;;
    docker-default) seccomp=$work/docker-default.json ;;
    shipped) seccomp=$root/deploy/seccomp/mbstorm-io_uring.json ;;
  esac
  in_container "$seccomp" mbstorm --version
  if [ $profile = shipped ]; then check "$profile: --version" 0 "$features"
  else check "$profile: --version" 0 "$blocked"; fi
  in_container "$seccomp" sh -c "$serve_then_run"
  if [ $profile = shipped ]; then
    check "$profile: 1-s run against serve, on io_uring" 0 "listening on .*, io_uring," "^Errors +0 of [0-9,]+ "
  else
    check "$profile: 1-s run against serve, on epoll" 0 "listening on .*epoll" \
      "backend: epoll; io_uring_setup refused" "^Errors +0 of [0-9,]+ "
  fi
done
exit $fail
