#!/usr/bin/env bash
# deploy/kubernetes/: no cluster runs here, so the manifests are loaded and checked for what
# the sharded test needs: an Indexed Job with parallelism == completions == MBSTORM_SHARD_COUNT
# whose pods take their shard from the environment (no --shard) and run with --start-at,
# --json, --hlog and --test-id onto a ReadWriteMany volume; a merge Job over the same files
# with the same shard count whose exit code is the verdict; the image recipe installs the
# project's .deb on Debian 12 slim. Every pod passes the "restricted" Pod Security Standard
# (issue #32): not root (runAsNonRoot, a non-zero runAsUser that is the image's numeric USER), no
# privilege escalation, capabilities dropped (ALL, none added but NET_BIND_SERVICE), seccomp
# RuntimeDefault or Localhost, no host namespaces, ports or paths, only the volume types it
# allows; the shards' pod names the Localhost opt-in (deploy/seccomp/'s profile) in a comment.
#   bash kubernetes_manifests.sh <mbstorm-binary> <scripts-dir>
set -u
deploy=$(cd "$2/../../deploy/kubernetes" && pwd) || { echo "FAIL no deploy/kubernetes"; exit 1; }
/usr/bin/python3 - "$deploy" <<'PY'
import glob, os, re, sys
import yaml

deploy = sys.argv[1]
docs = []
for path in sorted(glob.glob(os.path.join(deploy, "*.yaml"))):
    with open(path) as f:
        docs += [(os.path.basename(path), d) for d in yaml.safe_load_all(f) if d]
problems = []
def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what)
    if not cond: problems.append(what)

by_kind = {}
for name, d in docs:
    by_kind.setdefault(d["kind"], []).append(d)
jobs = {j["metadata"]["name"]: j for j in by_kind.get("Job", [])}
check(set(jobs) == {"mbstorm-shards", "mbstorm-merge"}, f"two Jobs, shards and merge ({sorted(jobs)})")
shards, merge = jobs.get("mbstorm-shards"), jobs.get("mbstorm-merge")
if not (shards and merge):
    sys.exit(1)

def env_of(container):
    return {e["name"]: e for e in container.get("env", [])}
def script_of(container):
    return " ".join(container.get("command", []) + container.get("args", []))

spec = shards["spec"]
check(spec.get("completionMode") == "Indexed", "shards: completionMode Indexed")
n = spec.get("completions")
check(isinstance(n, int) and n >= 1 and spec.get("parallelism") == n,
      f"shards: parallelism == completions ({spec.get('parallelism')} vs {n})")
check(spec.get("backoffLimit") == 0, "shards: backoffLimit 0 (a shard run twice would start late)")
pod = spec["template"]["spec"]
check(pod.get("restartPolicy") == "Never", "shards: restartPolicy Never")
(shard,) = pod["containers"]
env = env_of(shard)
check(env.get("MBSTORM_SHARD_COUNT", {}).get("value") == str(n),
      f"shards: MBSTORM_SHARD_COUNT == completions ({env.get('MBSTORM_SHARD_COUNT')})")
run = script_of(shard)
check("mbstorm run" in run, "shards: run mbstorm run")
check("--shard" not in run and "$JOB_COMPLETION_INDEX" in run,
      "shards: the shard from the environment (JOB_COMPLETION_INDEX, no --shard), files named by it")
for flag, var in (("--start-at", "START_AT"), ("--test-id", "TEST_ID"), ("--target", "TARGET")):
    check(re.search(flag + r' "\$' + var + '"', run) is not None and var in env,
          f"shards: {flag} from {var}, which the pod's env sets")
for flag in ("--json", "--hlog"):
    check(re.search(flag + r' "\$out/shard-\$JOB_COMPLETION_INDEX\.', run) is not None,
          f"shards: {flag} into the results volume, one file per shard")
check(".done" in run, "shards: a .done file marks a finished shard for the merge step")
mounts = {m["mountPath"]: m["name"] for m in shard.get("volumeMounts", [])}
volumes = {v["name"]: v for v in pod.get("volumes", [])}
claim = volumes.get(mounts.get("/results"), {}).get("persistentVolumeClaim", {}).get("claimName")
check(claim is not None, f"shards: /results is a persistent volume claim ({claim})")

mspec = merge["spec"]
check(mspec.get("completionMode", "NonIndexed") == "NonIndexed" and mspec.get("completions", 1) == 1,
      "merge: one pod")
check(mspec.get("backoffLimit") == 0, "merge: backoffLimit 0 (its exit code is the verdict)")
mpod = mspec["template"]["spec"]
(mc,) = mpod["containers"]
menv = env_of(mc)
check(menv.get("MBSTORM_SHARD_COUNT", {}).get("value") == str(n), "merge: the same shard count")
mscript = script_of(mc)
check(re.search(r'exec mbstorm merge "\$out"/shard-\*\.json "\$out"/shard-\*\.hlog', mscript) is not None,
      "merge: exec mbstorm merge over every shard's JSON and log (its exit code is the pod's)")
check('--expect "$MBSTORM_SHARD_COUNT"' in mscript, "merge: --expect the shard count")
check(".done" in mscript, "merge: waits for every shard's .done")
mmounts = {m["mountPath"]: m["name"] for m in mc.get("volumeMounts", [])}
mclaim = {v["name"]: v for v in mpod.get("volumes", [])}.get(mmounts.get("/results"), {}) \
    .get("persistentVolumeClaim", {}).get("claimName")
check(mclaim == claim, f"merge: reads the shards' volume ({mclaim})")

pvcs = {p["metadata"]["name"]: p for p in by_kind.get("PersistentVolumeClaim", [])}
check(claim in pvcs and "ReadWriteMany" in pvcs[claim]["spec"]["accessModes"],
      "the results claim exists and is ReadWriteMany (pods on many nodes)")
maps = {c["metadata"]["name"]: c for c in by_kind.get("ConfigMap", [])}
refs = set()
for c in (shard, mc):
    for e in c.get("env", []):
        ref = e.get("valueFrom", {}).get("configMapKeyRef")
        if ref: refs.add((ref["name"], ref["key"]))
for name, key in sorted(refs):
    check(key in maps.get(name, {}).get("data", {}), f"config {name}/{key} exists")
data = maps.get("mbstorm-test", {}).get("data", {})
scenario = yaml.safe_load(data.get("scenario.yaml", "")) or {}
check("operations" in scenario and "thresholds" in scenario, "the test's scenario has operations and thresholds")

with open(os.path.join(deploy, "Containerfile")) as f:
    recipe = f.read()
check(re.search(r"^FROM debian:12-slim", recipe, re.M) is not None, "Containerfile: FROM debian:12-slim")
check(re.search(r"^COPY mbstorm_\*\.deb", recipe, re.M) is not None and
      "apt-get install -y --no-install-recommends ./mbstorm_*.deb" in recipe,
      "Containerfile: installs the project's mbstorm_*.deb with apt-get")

# The "restricted" Pod Security Standard (kubernetes.io/docs/concepts/security/pod-security-standards).
user = re.search(r"^USER (\d+)(:\d+)?\s*$", recipe, re.M)
image_uid = int(user.group(1)) if user else None
check(image_uid not in (None, 0), f"Containerfile: USER is a numeric non-root uid ({image_uid})")
RESTRICTED_VOLUMES = {"configMap", "csi", "downwardAPI", "emptyDir", "ephemeral",
                      "persistentVolumeClaim", "projected", "secret"}
def seccomp_ok(context):
    kind = context.get("seccompProfile", {}).get("type")
    return kind in ("RuntimeDefault", "Localhost")
def restricted(job):
    name = job["metadata"]["name"]
    pod = job["spec"]["template"]["spec"]
    ctx = pod.get("securityContext", {})
    check(ctx.get("runAsNonRoot") is True, f"{name}: runAsNonRoot")
    check(ctx.get("runAsUser") == image_uid, f"{name}: runAsUser is the image's uid ({ctx.get('runAsUser')})")
    check(ctx.get("seccompProfile", {}).get("type") == "RuntimeDefault", f"{name}: pod seccompProfile RuntimeDefault")
    check(not any(pod.get(k) for k in ("hostNetwork", "hostPID", "hostIPC")), f"{name}: no host namespaces")
    kinds = {k for v in pod.get("volumes", []) for k in v if k != "name"}
    check(kinds <= RESTRICTED_VOLUMES, f"{name}: only restricted volume types ({sorted(kinds)})")
    for c in pod["containers"] + pod.get("initContainers", []):
        cctx = c.get("securityContext", {})
        caps = cctx.get("capabilities", {})
        check(cctx.get("allowPrivilegeEscalation") is False, f"{name}/{c['name']}: allowPrivilegeEscalation false")
        check("ALL" in caps.get("drop", []) and set(caps.get("add", [])) <= {"NET_BIND_SERVICE"},
              f"{name}/{c['name']}: capabilities drop ALL, none added ({caps})")
        check(not cctx.get("privileged") and cctx.get("runAsUser", 1) != 0 and
              cctx.get("runAsNonRoot", True) is True and ("seccompProfile" not in cctx or seccomp_ok(cctx)),
              f"{name}/{c['name']}: not privileged, not root, no seccomp override but RuntimeDefault/Localhost")
        check(not any("hostPort" in p for p in c.get("ports", [])), f"{name}/{c['name']}: no host ports")
for job in (shards, merge):
    restricted(job)
with open(os.path.join(deploy, "shards-job.yaml")) as f:
    opt_in = re.search(r"^\s*#\s*seccompProfile: \{type: Localhost, localhostProfile: profiles/(\S+)\}$",
                       f.read(), re.M)
profile = opt_in and os.path.join(deploy, "..", "seccomp", opt_in.group(1))
check(opt_in is not None and os.path.isfile(profile),
      f"shards: the Localhost opt-in, commented, names deploy/seccomp/'s profile ({opt_in and opt_in.group(1)})")
sys.exit(1 if problems else 0)
PY
