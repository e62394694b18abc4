#!/usr/bin/env bash
# Runs every libFuzzer target (fuzz_* executables of a RACKCAT_FUZZ=ON build) on its seed
# corpus for a bounded time. Any crash, leak or sanitizer report fails; every target runs even after
# one fails, and a summary lists each target's result (exit 1 if any failed).
#
#   scripts/fuzz.sh [--build-dir DIR] [--seconds N | --minutes N]
#
# The seed corpus of target fuzz_X is fuzz/corpus/X/ (kept small in the repo; cut from real
# traffic by fuzz/seed_corpora.py), plus fuzz/<area>/corpus/ when an area keeps its own (area =
# X up to the first underscore); new inputs are written to a scratch copy under
# fuzz/corpus-work/ (git-ignored), never into the repo. JOBS limits the build (default nproc).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=build-fuzz
SECONDS_PER_TARGET=60
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) BUILD=$2; shift 2 ;;
    --seconds) SECONDS_PER_TARGET=$2; shift 2 ;;
    --minutes) SECONDS_PER_TARGET=$(( $2 * 60 )); shift 2 ;;
    *) echo "usage: scripts/fuzz.sh [--build-dir DIR] [--seconds N | --minutes N]" >&2; exit 2 ;;
  esac
done
if [ ! -d "$BUILD" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DRACKCAT_SANITIZE=ON -DRACKCAT_FUZZ=ON -DRACKCAT_BENCH=OFF >/dev/null
fi
cmake --build "$BUILD" -j "${JOBS:-$(nproc)}" >/dev/null
mapfile -t targets < <(find "$BUILD" -maxdepth 3 -type f -name 'fuzz_*' -perm -u+x | sort)
if [ ${#targets[@]} -eq 0 ]; then echo "fuzz: no targets built"; exit 1; fi
failed=()
summary=()
for t in "${targets[@]}"; do
  name=$(basename "$t"); name=${name#fuzz_}
  work=fuzz/corpus-work/$name
  mkdir -p "$work"
  [ -d "fuzz/corpus/$name" ] && cp -n fuzz/corpus/"$name"/* "$work"/ 2>/dev/null || true
  area=${name%%_*}
  [ -d "fuzz/$area/corpus" ] && cp -n fuzz/"$area"/corpus/* "$work"/ 2>/dev/null || true
  echo "fuzz: $name for ${SECONDS_PER_TARGET}s"
  log=fuzz/corpus-work/$name.log
  # One failing target does not hide the others: every target runs, each is reported.
  if ASAN_OPTIONS=detect_leaks=1 "$t" -max_total_time="$SECONDS_PER_TARGET" -print_final_stats=1 \
    -artifact_prefix="fuzz/corpus-work/crash-$name-" "$work" >"$log" 2>&1; then
    grep -E '^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)|cov: ' "$log" | tail -n 4 || true
    runs=$(grep -E '^stat::number_of_executed_units' "$log" | awk '{print $2}' | tail -n 1 || true)
    summary+=("$(printf '  %-28s ok      %s runs' "$name" "${runs:-?}")")
  else
    rc=$?
    tail -n 60 "$log"
    echo "fuzz: $name FAILED (exit $rc; log $log, artifacts fuzz/corpus-work/crash-$name-*)"
    failed+=("$name")
    summary+=("$(printf '  %-28s FAILED  exit %s, %s' "$name" "$rc" "$log")")
  fi
done
echo "fuzz: summary (${#targets[@]} targets, ${SECONDS_PER_TARGET}s each)"
printf '%s\n' "${summary[@]}"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: ${#failed[@]} of ${#targets[@]} targets FAILED: ${failed[*]}"
  exit 1
fi
echo "fuzz: all ${#targets[@]} targets passed"
