#!/usr/bin/env bash
# Installs every Debian 12 package mbstorm needs to build, test, fuzz and benchmark, then checks
# that every program and python module the tests use (scripts/test-needs.txt) is there.
# Idempotent: packages already present are skipped; runs apt-get only when something is missing.
#   bash scripts/setup.sh           install what is missing, then check
#   bash scripts/setup.sh --check   only check (exit 1 naming what is missing)
set -euo pipefail
cd "$(dirname "$0")"
needs_file=test-needs.txt

# To build (the tests' own programs and modules come from test-needs.txt).
packages=(
  build-essential g++ cmake ninja-build pkg-config git
  clang libclang-rt-14-dev clang-format
  liburing-dev libgtest-dev libgmock-dev googletest libbenchmark-dev
  libcli11-dev libyaml-cpp-dev nlohmann-json3-dev libfmt-dev libmodbus-dev
  zlib1g-dev
  libseccomp-dev   # tests/tools/seccomp_run: seccomp filters as container runtimes apply them
  libssl-dev   # --transport tls (Modbus/TCP Security): OpenSSL
  dpkg-dev   # cpack -G DEB: dpkg-shlibdeps finds the package's dependencies
  help2man   # the man pages, written at build time from mbstorm's own --help
  bash-completion   # tests/scripts/bash_completion.sh loads the completion as a shell would
  procps util-linux
)
# Lines of test-needs.txt: kind name package...
while read -r kind name pkgs; do
  case "$kind" in ''|'#'*) continue ;; esac
  read -ra list <<<"$pkgs"
  packages+=("${list[@]}")
done <"$needs_file"
mapfile -t packages < <(printf '%s\n' "${packages[@]}" | sort -u)

# check_needs: every program on PATH, every module importable by /usr/bin/python3, every
# library known to pkg-config.
check_needs() {
  local missing=() kind name pkgs
  while read -r kind name pkgs; do
    case "$kind" in
      program) command -v "$name" >/dev/null || missing+=("program $name ($pkgs)") ;;
      module) /usr/bin/python3 -c "import $name" >/dev/null 2>&1 || missing+=("python module $name ($pkgs)") ;;
      library) pkg-config --exists "$name" 2>/dev/null || missing+=("library $name ($pkgs)") ;;
    esac
  done <"$needs_file"
  if [ ${#missing[@]} -ne 0 ]; then
    echo "setup: the tests need what is not installed:" >&2
    printf '  %s\n' "${missing[@]}" >&2
    return 1
  fi
  echo "setup: every program, python module and library in scripts/$needs_file is present"
}

if [ "${1:-}" = --check ]; then check_needs; exit; fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
else
  echo "setup: installing ${missing[*]}"
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null; then sudo_cmd=(sudo); else
      echo "setup: need root (or sudo) to install: ${missing[*]}" >&2; exit 1
    fi
  fi
  export DEBIAN_FRONTEND=noninteractive
  # tshark asks whether non-root users may capture; answer "no" without a prompt.
  echo "wireshark-common wireshark-common/install-setuid boolean false" | "${sudo_cmd[@]}" debconf-set-selections 2>/dev/null || true
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
check_needs
