#!/usr/bin/env bash
# Installs what rackcat needs, from Debian's packages and PyPI. Two profiles:
#
#   scripts/setup.sh --demo   what scripts/demo.sh needs: the compiler, CMake, the libraries the
#                             CLI links, node + npm (the build bundles the web page with esbuild,
#                             which it installs from npm itself), iproute2, and pysoem in the
#                             project's virtual environment
#   scripts/setup.sh          everything the tests need on top (scripts/test.sh): clang and its
#                             tools, GoogleTest/Benchmark, tshark, QEMU with a kernel image and
#                             busybox for the CAN VM test, pytest, chromium and web/'s npm
#                             test tools (TypeScript, ESLint, playwright-core)
#
# Python packages go into a virtual environment in the checkout (.venv, created with Debian's
# python3-venv), never into the system interpreter. Every script runs Python through
# scripts/python.sh, which picks that environment. Other helpers add PyPI packages to
# PY_TEST_PACKAGES (or PY_DEMO_PACKAGES) below, nowhere else.
#
# Idempotent: a second run installs nothing and finishes in a few seconds. It says what it
# installs; apt's and pip's own progress is shown.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)

PROFILE=test
case "${1:-}" in
  --demo) PROFILE=demo ;;
  "" | --test) ;;
  *) echo "usage: scripts/setup.sh [--demo|--test]" >&2; exit 2 ;;
esac

# Building the CLI and running the demo (scripts/demo.sh).
DEB_DEMO=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libpugixml-dev libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev
  nlohmann-json3-dev libcpp-httplib-dev libssl-dev zlib1g-dev
  iproute2 python3 python3-venv
)
# The tests on top (scripts/test.sh): sanitizer/fuzz builds, tidy, unit tests, capture checks,
# the CAN VM test.
DEB_TEST=(
  clang clang-format clang-tidy libclang-rt-14-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  tshark libxml2-utils
  qemu-system-x86 linux-image-amd64 busybox-static
  libpcap-dev python3-dev
  chromium
)
PY_DEMO_PACKAGES=(pysoem)
PY_TEST_PACKAGES=(pytest)
# The EtherCAT masters of the conformance matrix (tests/conformance, docs/INTEROP.md), pinned:
# a new release is adopted by changing the version here and re-running the matrix. soemx
# builds from source against libpcap (libpcap-dev, python3-dev above). mypy checks the types
# of python/rackcat_line, the master developers' package (it ships py.typed).
PY_TEST_PINNED=(kickcat==2.5 soemx==0.1.1 pyecm==0.0.3 ebpfcat==1.0.0 mypy==1.13.0)

deb=("${DEB_DEMO[@]}")
py=("${PY_DEMO_PACKAGES[@]}")
if [ "$PROFILE" = test ]; then
  deb+=("${DEB_TEST[@]}")
  py+=("${PY_TEST_PACKAGES[@]}")
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${deb[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# node and npm build the web page (web/, docs/WEB.md). Debian's nodejs + npm unless a node with
# its npm is already there (another distribution of node ships npm inside its nodejs package).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  missing+=(nodejs npm)
fi
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${#missing[@]} Debian package(s): ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  echo "wireshark-common wireshark-common/install-setuid boolean false" | $SUDO debconf-set-selections || true
  echo "setup: apt-get update"
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "setup: Debian packages ($PROFILE profile) already installed"
fi

# The project's virtual environment. PYTHON selects the interpreter that creates it.
VENV=$ROOT/.venv
if [ ! -x "$VENV/bin/python" ]; then
  echo "setup: creating the Python virtual environment $VENV"
  "${PYTHON:-python3}" -m venv "$VENV"
fi
need_py=()
for p in "${py[@]}"; do
  "$VENV/bin/python" -c "import $p" 2>/dev/null || need_py+=("$p")
done
if [ ${#need_py[@]} -gt 0 ]; then
  echo "setup: installing Python package(s) into .venv: ${need_py[*]}"
  "$VENV/bin/python" -m pip install --disable-pip-version-check --progress-bar off "${need_py[@]}"
fi
if [ "$PROFILE" = test ]; then
  need_pinned=()
  for spec in "${PY_TEST_PINNED[@]}"; do
    have=$("$VENV/bin/python" -c "import importlib.metadata as m; print(m.version('${spec%%==*}'))" \
      2>/dev/null || true)
    [ "$have" = "${spec#*==}" ] || need_pinned+=("$spec")
  done
  if [ ${#need_pinned[@]} -gt 0 ]; then
    echo "setup: installing pinned test packages into .venv: ${need_pinned[*]}"
    "$VENV/bin/python" -m pip install --disable-pip-version-check --progress-bar off \
      "${need_pinned[@]}"
  fi
fi
# The master developers' package (python/rackcat_line), editable, when present.
if [ "$PROFILE" = test ] && [ -f "$ROOT/python/pyproject.toml" ] &&
  ! "$VENV/bin/python" -c "import rackcat_line" 2>/dev/null; then
  echo "setup: installing python/ (rackcat_line) into .venv"
  "$VENV/bin/python" -m pip install --disable-pip-version-check --progress-bar off -e "$ROOT/python"
fi
# The web page's test tools (web/package.json devDependencies: TypeScript, ESLint,
# playwright-core driving Debian's chromium). The build alone installs only esbuild.
if [ "$PROFILE" = test ] && [ ! -d "$ROOT/web/node_modules/playwright-core" ]; then
  echo "setup: npm ci in web/ (the web page's lint, unit tests and browser test)"
  (cd "$ROOT/web" && npm ci --no-audit --no-fund --loglevel=error)
fi
echo "setup: ok ($PROFILE profile)"
