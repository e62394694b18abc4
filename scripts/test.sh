#!/usr/bin/env bash
# Sets up and runs every test of rackcat: the README's test command, and what CI runs.
#
#   1. scripts/setup.sh (Debian + PyPI packages, idempotent)
#   2. release build (gcc) -> GoogleTest suite under ctest, then clang-tidy over the library
#      and app sources (scripts/tidy.sh: any finding fails)
#   3. wire interop against real masters over veth pairs in private network namespaces:
#      pysoem (pytest, tests/interop) and ethercrab (scripts/ethercrab_interop.sh); they skip
#      with a message when not root
#   4. sanitizer build (clang, ASan+UBSan, with the libFuzzer targets) -> the whole ctest suite
#      again, then every fuzz target for a bounded time on its seed corpus
#   5. a short bounded soak run (scripts/soak.sh), when present
#
# Environment: JOBS (default: nproc), FUZZ_SECONDS (default 60 per target), SKIP_ASAN=1,
# SKIP_FUZZ=1, SKIP_INTEROP=1 for quicker local runs.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
JOBS=${JOBS:-$(nproc)}
FUZZ_SECONDS=${FUZZ_SECONDS:-60}

step() { printf '\n==== %s ====\n' "$*"; }
started=$(date +%s)

step "setup"
bash scripts/setup.sh

step "release build"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$JOBS"

step "unit tests (release)"
ctest --test-dir build --output-on-failure -j "$JOBS" --timeout 300

step "clang-tidy (library and app sources)"
bash scripts/tidy.sh build

if [ "${SKIP_INTEROP:-0}" != 1 ]; then
  step "interop: pysoem over veth"
  rc=0
  python3 -m pytest -q tests/interop -p no:cacheprovider || rc=$?
  # pytest exits 5 when it collected no test at all: that is a failure here.
  if [ "$rc" -ne 0 ]; then echo "pytest failed with exit code $rc"; exit 1; fi
  if [ -f scripts/ethercrab_interop.sh ]; then
    step "interop: ethercrab over veth"
    bash scripts/ethercrab_interop.sh
  fi
fi

if [ "${SKIP_ASAN:-0}" != 1 ]; then
  step "sanitizer build (clang, ASan+UBSan, libFuzzer targets)"
  CC=clang CXX=clang++ cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DRACKCAT_SANITIZE=ON -DRACKCAT_FUZZ=ON -DRACKCAT_BENCH=OFF >/dev/null
  cmake --build build-asan -j "$JOBS"
  step "unit tests (ASan+UBSan)"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j "$JOBS" --timeout 600
  if [ "${SKIP_FUZZ:-0}" != 1 ] && [ -x scripts/fuzz.sh ]; then
    step "fuzz (${FUZZ_SECONDS}s per target)"
    bash scripts/fuzz.sh --build-dir build-asan --seconds "$FUZZ_SECONDS"
  fi
fi

if [ -f scripts/soak.sh ] && [ "${SKIP_INTEROP:-0}" != 1 ]; then
  step "soak (bounded)"
  bash scripts/soak.sh --minutes 1
fi

echo
echo "all tests passed in $(( $(date +%s) - started )) s"
