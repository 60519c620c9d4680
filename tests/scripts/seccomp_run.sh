#!/usr/bin/env bash
# tests/tools/seccomp_run, the launcher that stands in for a container runtime's seccomp filter
# (issue #32): under --deny-io-uring a child's io_uring_queue_init (liburing) gets EPERM, as
# under Docker's default profile, while everything else and the same child without the filter
# run; --profile FILE applies an OCI/Docker profile the way it documents (errnoRet, args,
# includes.caps, includes.arches), each rule shown by a profile that hinges on it.
#   bash seccomp_run.sh <mbstorm-binary> <scripts-dir>
set -u
bin_dir=$(cd "$(dirname "$1")" && pwd)
launcher="$bin_dir/tests/seccomp_run"
probe="$bin_dir/tests/io_uring_probe"
[ -x "$launcher" ] || {
  echo "skip: $launcher was not built: libseccomp-dev is not installed (scripts/setup.sh installs it)"
  exit 77
}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail=0

# expect NAME WANT-EXIT WANT-OUTPUT COMMAND...: COMMAND's exit and the first line it printed.
expect() {
  local name=$1 want_rc=$2 want_out=$3; shift 3
  "$@" >"$work/out" 2>&1
  local rc=$? out
  out=$(head -1 "$work/out")
  if [ "$rc" = "$want_rc" ] && [[ "$out" == $want_out ]]; then
    echo "ok   $name: exit $rc, '$out'"
  else
    echo "FAIL $name: exit $rc (want $want_rc), '$out' (want '$want_out')"
    fail=1
  fi
}

"$probe" >"$work/alone" 2>&1 ||
  { echo "skip: io_uring is not available here: $(cat "$work/alone")"; exit 77; }
expect "the probe alone sets up a ring" 0 "io_uring_queue_init: 0" "$probe"
expect "--deny-io-uring: EPERM" 1 "io_uring_queue_init: -1 (Operation not permitted)" \
  "$launcher" --deny-io-uring -- "$probe"
expect "--deny-io-uring leaves other calls alone" 0 "forked" \
  "$launcher" --deny-io-uring -- sh -c '(echo forked) | cat'
expect "usage error" 2 "usage: seccomp_run*" "$launcher" --deny-io-uring "$probe"
expect "unreadable profile" 125 "seccomp_run: cannot open*" "$launcher" --profile "$work/none.json" -- true
expect "missing program" 127 "seccomp_run: cannot execute*" "$launcher" --deny-io-uring -- "$work/none"

# profile NAME FIELDS: a profile allowing every call, but io_uring_setup in an entry with
# action ERRNO and FIELDS (its conditions). Skipped, the ring is set up; applied, EPERM.
profile() {
  cat >"$work/$1.json" <<EOF
{"defaultAction": "SCMP_ACT_ALLOW",
 "syscalls": [{"names": ["io_uring_setup"], "action": "SCMP_ACT_ERRNO"$2}]}
EOF
  echo "$work/$1.json"
}
under() { "$launcher" --profile "$(profile "$1" "$2")" -- "$probe"; }
set_up="io_uring_queue_init: 0"
denied="io_uring_queue_init: -1 (Operation not permitted)"
expect "profile: an entry applies" 1 "$denied" under plain ''
expect "profile: errnoRet" 1 "io_uring_queue_init: -38 (Function not implemented)" \
  under errno ', "errnoRet": 38'
expect "profile: an entry granted to a capability is skipped" 0 "$set_up" \
  under caps ', "includes": {"caps": ["CAP_SYS_ADMIN"]}'
expect "profile: an entry for holders of no capability applies" 1 "$denied" \
  under nocaps ', "excludes": {"caps": ["CAP_SYS_ADMIN"]}'
expect "profile: an entry of another arch is skipped" 0 "$set_up" \
  under arm ', "includes": {"arches": ["arm", "arm64"]}'
expect "profile: an entry of amd64 applies" 1 "$denied" \
  under amd64 ', "includes": {"arches": ["amd64", "x32"]}'
expect "profile: an entry excluded from amd64 is skipped" 0 "$set_up" \
  under notamd64 ', "excludes": {"arches": ["amd64"]}'
expect "profile: an entry for a later kernel is skipped" 0 "$set_up" \
  under kernel99 ', "includes": {"minKernel": "99.0"}'
expect "profile: an entry for this kernel applies" 1 "$denied" \
  under kernel48 ', "includes": {"minKernel": "4.8"}'
# io_uring_probe asks for 8 entries (io_uring_setup's first argument); its second, the
# parameters' address, is never 0.
expect "profile: args that match" 1 "$denied" \
  under args8 ', "args": [{"index": 0, "value": 8, "op": "SCMP_CMP_EQ"}]'
expect "profile: args that do not" 0 "$set_up" \
  under args16 ', "args": [{"index": 0, "value": 16, "op": "SCMP_CMP_EQ"}]'
expect "profile: MASKED_EQ, value the mask and valueTwo the datum" 1 "$denied" \
  under masked ', "args": [{"index": 0, "value": 12, "valueTwo": 8, "op": "SCMP_CMP_MASKED_EQ"}]'
expect "profile: MASKED_EQ that does not match" 0 "$set_up" \
  under masked0 ', "args": [{"index": 0, "value": 12, "valueTwo": 0, "op": "SCMP_CMP_MASKED_EQ"}]'
expect "profile: two conditions on one argument are ORed" 1 "$denied" \
  under either ', "args": [{"index": 0, "value": 16, "op": "SCMP_CMP_EQ"},
                           {"index": 0, "value": 8, "op": "SCMP_CMP_EQ"}]'
expect "profile: conditions on two arguments are ANDed" 0 "$set_up" \
  under both ', "args": [{"index": 0, "value": 8, "op": "SCMP_CMP_EQ"},
                         {"index": 1, "value": 0, "op": "SCMP_CMP_EQ"}]'
printf '{"defaultAction": "SCMP_ACT_NOTIFY"}' >"$work/bad.json"
expect "profile: an unsupported action is refused" 125 "seccomp_run: unsupported action*" \
  "$launcher" --profile "$work/bad.json" -- true
exit $fail
