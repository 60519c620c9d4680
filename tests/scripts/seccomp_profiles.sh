#!/usr/bin/env bash
# deploy/seccomp/mbstorm-io_uring.json, the profile shipped for Docker, Podman and Kubernetes'
# Localhost seccomp (issue #32), is Docker's default profile plus io_uring_setup, io_uring_enter
# and io_uring_register. Offline: it is JSON in Docker's format, denying with EPERM by default;
# the three calls are allowed, unconditionally, in an entry of their own and named nowhere else;
# without them ("the default", derived here so the shipped file is the one source) it has as many
# entries and calls as deploy/seccomp/README.md says Docker's default has. Applied with
# tests/tools/seccomp_run: mbstorm --version and run --help run under both profiles (not killed);
# io_uring_probe and mbstorm (--version's io_uring line, serve for 1 s) get io_uring under the
# shipped profile and EPERM without the three calls, where serve runs on epoll and says why.
#   bash seccomp_profiles.sh <mbstorm-binary> <scripts-dir>
set -u
mbstorm=$1
root=$(cd "$2/../.." && pwd)
bin_dir=$(cd "$(dirname "$mbstorm")" && pwd)
launcher="$bin_dir/tests/seccomp_run"
probe="$bin_dir/tests/io_uring_probe"
shipped="$root/deploy/seccomp/mbstorm-io_uring.json"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0

/usr/bin/python3 - "$shipped" "$root/deploy/seccomp/README.md" "$work/default.json" <<'PY' || fail=1
import json, re, sys

shipped_path, readme_path, default_path = sys.argv[1:]
IO_URING = {"io_uring_setup", "io_uring_enter", "io_uring_register"}
problems = []
def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond: problems.append(what)

try:
    shipped = json.load(open(shipped_path))
except ValueError as e:
    check(False, f"the profile is JSON ({e})")
    sys.exit(1)
entries = shipped.get("syscalls", [])
check(shipped.get("defaultAction") == "SCMP_ACT_ERRNO" and shipped.get("defaultErrnoRet") == 1,
      "a call the profile does not name fails with EPERM, as under Docker's default")
check(all(isinstance(e.get("names"), list) and e.get("action", "").startswith("SCMP_ACT_") for e in entries),
      "every entry has names and an action")
own = [e for e in entries if set(e["names"]) & IO_URING]
check(len(own) == 1 and set(own[0]["names"]) == IO_URING and own[0]["action"] == "SCMP_ACT_ALLOW" and
      not set(own[0]) - {"names", "action", "comment"},
      "the three io_uring calls: allowed unconditionally, in one entry of their own, named nowhere else")

# Docker's default: the shipped profile with the three calls taken out.
default = dict(shipped)
default["syscalls"] = [dict(e, names=[n for n in e["names"] if n not in IO_URING]) for e in entries]
default["syscalls"] = [e for e in default["syscalls"] if e["names"]]
json.dump(default, open(default_path, "w"))
def calls(profile):
    return {n for e in profile["syscalls"] for n in e["names"]}
def allowed(profile):
    return {n for e in profile["syscalls"] if e["action"] == "SCMP_ACT_ALLOW" and
            not set(e) - {"names", "action", "comment"} for n in e["names"]}
check(calls(shipped) - calls(default) == IO_URING and allowed(shipped) - allowed(default) == IO_URING,
      "the shipped profile allows the three io_uring calls more than the default, nothing else")
stated = re.search(r"(\d+)\s+entries\s+naming\s+(\d+)\s+system\s+calls", open(readme_path).read())
counts = (len(default["syscalls"]), len(calls(default)))
check(stated is not None and (int(stated[1]), int(stated[2])) == counts,
      f"without them, {counts[0]} entries naming {counts[1]} system calls, as README.md states"
      f" ({' '.join(stated[0].split()) if stated else 'no such sentence'})")
sys.exit(1 if problems else 0)
PY

[ -x "$launcher" ] || {
  echo "skip: $launcher was not built: libseccomp-dev is not installed (scripts/setup.sh installs it)"
  exit 77
}
"$probe" >"$work/alone" 2>&1 ||
  { echo "skip: io_uring is not available here: $(cat "$work/alone")"; exit 77; }

# expect NAME WANT-EXIT WANT-LINE COMMAND...: COMMAND's exit and a line of its output.
expect() {
  local name=$1 want_rc=$2 want_line=$3; shift 3
  "$@" >"$work/out" 2>&1
  local rc=$?
  if [ "$rc" = "$want_rc" ] && grep -qx -- "$want_line" "$work/out"; then
    echo "ok   $name: exit $rc"
  else
    echo "FAIL $name: exit $rc (want $want_rc), no line '$want_line' in:"
    sed 's/^/  /' "$work/out" | head -20
    fail=1
  fi
}
under_shipped() { "$launcher" --profile "$shipped" -- "$@"; }
under_default() { "$launcher" --profile "$work/default.json" -- "$@"; }

expect "shipped: io_uring_probe sets up a ring" 0 "io_uring_queue_init: 0" under_shipped "$probe"
expect "default: io_uring_probe gets EPERM" 1 "io_uring_queue_init: -1 (Operation not permitted)" \
  under_default "$probe"
features="io_uring (kernel $(uname -r)): [a-z_ ]*multishot_accept.*"
blocked="io_uring (kernel $(uname -r)): unavailable (kernel too old, or io_uring blocked)"
expect "shipped: mbstorm --version sees io_uring" 0 "$features" under_shipped "$mbstorm" --version
expect "default: mbstorm --version runs, io_uring blocked" 0 "$blocked" under_default "$mbstorm" --version
for profile in shipped default; do
  expect "$profile: mbstorm run --help" 0 "Usage: mbstorm run .*" "under_$profile" "$mbstorm" run --help
done
expect "shipped: mbstorm serve on io_uring for 1 s" 0 "mbstorm serve: listening on .*, io_uring,.*" \
  under_shipped "$mbstorm" serve -d 1s --listen 127.0.0.1:0
# Without the three calls serve runs on the portable backend (issue #32).
expect "default: mbstorm serve on epoll for 1 s" 0 "mbstorm serve: listening on .*epoll.*" \
  under_default "$mbstorm" serve -d 1s --listen 127.0.0.1:0
exit $fail
