#!/usr/bin/env bash
# Installs everything rackcat needs to build, run and test, from Debian's packages and PyPI
# (and crates.io, through cargo, for the ethercrab interop program). Idempotent: a second run
# installs nothing and finishes in a few seconds.
set -euo pipefail

DEB_PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  clang clang-format clang-tidy libclang-rt-14-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libeigen3-dev libpugixml-dev libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev
  nlohmann-json3-dev libcpp-httplib-dev libssl-dev zlib1g-dev
  iproute2 tshark libxml2-utils python3 python3-pip python3-venv
  qemu-system-x86 linux-image-amd64 busybox-static
)
PY_PACKAGES=(pysoem pytest)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${DEB_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing Debian packages: ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  echo "wireshark-common wireshark-common/install-setuid boolean false" | $SUDO debconf-set-selections || true
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# Python test packages: into the interpreter that runs the tests (python3 on PATH).
PY=${PYTHON:-python3}
need_py=()
for p in "${PY_PACKAGES[@]}"; do
  "$PY" -c "import $p" 2>/dev/null || need_py+=("$p")
done
if [ ${#need_py[@]} -gt 0 ]; then
  echo "setup: installing Python packages: ${need_py[*]}"
  "$PY" -m pip install -q --disable-pip-version-check "${need_py[@]}" 2>/dev/null \
    || "$PY" -m pip install -q --disable-pip-version-check --break-system-packages "${need_py[@]}"
fi
echo "setup: ok"
