#!/usr/bin/env bash
# Sets up and runs every test of rackcat: the README's test command, and what CI runs.
#
#   1. scripts/setup.sh (Debian packages + PyPI packages into .venv, idempotent)
#   2. release build (gcc) -> GoogleTest suite under ctest, then clang-tidy over the library
#      and app sources (scripts/tidy.sh: any finding fails); the web page's TypeScript: ESLint,
#      tsc type check and its unit tests (node --test)
#   3. wire interop against real masters over veth pairs in private network namespaces:
#      pysoem (pytest, tests/interop; test_web_page.py drives the web page in Debian's
#      chromium headless and keeps build/web-page.png), ethercrab (scripts/ethercrab_interop.sh), then the
#      conformance matrix (tests/conformance: pysoem, soemx, pyecm, kickcat, ebpfcat,
#      ethercrab on three racks; rewrites docs/INTEROP.md's matrix); they skip with a message
#      when not root
#   4. sanitizer build (clang, ASan+UBSan, with the libFuzzer targets) -> the whole ctest suite
#      again, then every fuzz target for a bounded time on its seed corpus
#   5. a short bounded soak run (scripts/soak.sh), when present
#
# Every step runs even when an earlier one failed; the end is a summary of each step's result
# and time, and the exit status is non-zero when any step failed. Works from any checkout path
# (spaces included). Each step's output is also kept in build-logs/STEP.log.
#
# Environment: JOBS (default: nproc), FUZZ_SECONDS (default 60 per target), SKIP_ASAN=1,
# SKIP_FUZZ=1, SKIP_INTEROP=1 for quicker local runs.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$(pwd)
JOBS=${JOBS:-$(nproc)}
FUZZ_SECONDS=${FUZZ_SECONDS:-60}
LOGS=$ROOT/build-logs
mkdir -p "$LOGS"

names=()
results=()
times=()
failed=0
# step NAME FUNCTION: runs FUNCTION in a subshell with errexit, records result and time.
step() {
  local name=$1 fn=$2 t0 rc log
  log=$LOGS/$(tr -c 'A-Za-z0-9_-' '_' <<<"$name" | sed 's/_*$//').log
  printf '\n==== %s ====\n' "$name"
  t0=$(date +%s)
  ( set -euo pipefail; "$fn" ) 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  names+=("$name")
  times+=($(( $(date +%s) - t0 )))
  if [ "$rc" -eq 0 ]; then results+=("pass"); else results+=("FAIL ($rc)"); failed=1; fi
}

do_setup() { bash scripts/setup.sh; }
do_build() {
  cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DRACKCAT_TESTS=ON -DRACKCAT_BENCH=ON \
    >/dev/null
  cmake --build build -j "$JOBS"
}
do_unit() { ctest --test-dir build --output-on-failure -j "$JOBS" --timeout 300; }
do_tidy() { bash scripts/tidy.sh build; }
do_web() {
  cd web
  [ -d node_modules/playwright-core ] || npm ci --no-audit --no-fund --loglevel=error
  npm run --silent lint
  npm run --silent typecheck
  npm test
}
# python/rackcat_line promises types to its users (py.typed): they must hold.
do_pytypes() {
  . scripts/python.sh
  "$PY" -m mypy --strict --no-error-summary --cache-dir=/dev/null python/rackcat_line
}
do_pysoem() {
  . scripts/python.sh
  # pytest exits 5 when it collected no test at all: that is a failure here too.
  "$PY" -m pytest -q tests/interop -p no:cacheprovider
}
# The README's first command, as a new user runs it (setup --demo and the build are no-ops by
# now): the default rack to OP under pysoem from this checkout's path.
do_demo() { bash scripts/demo.sh --seconds 2; }
do_ethercrab() {
  bash scripts/ethercrab_interop.sh
  # the user's own line (docs/LINE.md): coupler, DI, DO, CoE terminal, rack; DO->DI wired
  bash scripts/ethercrab_interop.sh --test-line --cycles 2000
  # a line longer than SOEM configures (EC_MAXSLAVE 200): 256 tiny racks to OP, 2,000 cycles
  # with the working counter checked on each (ethercrab --mode op, as scripts/op_bench.py uses it)
  bash scripts/ethercrab_interop.sh --mode op --sizes 256 --cycles 2000 \
    --slave "build/rackcat run --config examples/tiny-rack.yaml"
}
do_conformance() {
  . scripts/python.sh
  # the conformance matrix: every master on every rack (tests/conformance, docs/INTEROP.md)
  "$PY" -m pytest -q tests/conformance -p no:cacheprovider
}
do_asan_build() {
  CC=clang CXX=clang++ cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DRACKCAT_SANITIZE=ON -DRACKCAT_FUZZ=ON -DRACKCAT_BENCH=OFF >/dev/null
  cmake --build build-asan -j "$JOBS"
}
do_asan_unit() {
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j "$JOBS" --timeout 600
}
do_fuzz() { bash scripts/fuzz.sh --build-dir build-asan --seconds "$FUZZ_SECONDS"; }
do_soak() { bash scripts/soak.sh --minutes 1; }

started=$(date +%s)
step "setup" do_setup
step "release build" do_build
step "unit tests (release)" do_unit
step "clang-tidy" do_tidy
step "web page: lint, types, unit tests" do_web
step "python package: types (mypy --strict)" do_pytypes
if [ "${SKIP_INTEROP:-0}" != 1 ]; then
  step "interop: pysoem over veth" do_pysoem
  step "demo (README's first command)" do_demo
  [ -f scripts/ethercrab_interop.sh ] && step "interop: ethercrab over veth" do_ethercrab
  step "interop: conformance matrix" do_conformance
fi
if [ "${SKIP_ASAN:-0}" != 1 ]; then
  step "sanitizer build" do_asan_build
  step "unit tests (ASan+UBSan)" do_asan_unit
  if [ "${SKIP_FUZZ:-0}" != 1 ] && [ -x scripts/fuzz.sh ]; then
    step "fuzz (${FUZZ_SECONDS}s per target)" do_fuzz
  fi
fi
if [ -f scripts/soak.sh ] && [ "${SKIP_INTEROP:-0}" != 1 ]; then
  step "soak (bounded)" do_soak
fi

echo
echo "==== summary ===="
for i in "${!names[@]}"; do
  printf '  %-34s %-10s %5d s\n' "${names[i]}" "${results[i]}" "${times[i]}"
done
total=$(( $(date +%s) - started ))
if [ "$failed" -ne 0 ]; then
  echo "some steps FAILED (total ${total} s); their output is in build-logs/"
  exit 1
fi
echo "all steps passed in ${total} s"
