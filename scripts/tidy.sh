#!/usr/bin/env bash
# Runs clang-tidy with the repo's .clang-tidy over every library and app source (base/ coe/ foe/ ecat/
# mdp/ modules/ esi/ apps/), two files at a time. Any finding is an error: the script prints
# each one, a one-line summary (files, findings, seconds) and exits 1.
#
#   scripts/tidy.sh [BUILD_DIR]      (default: build)
#
# BUILD_DIR must hold compile_commands.json (the root CMakeLists.txt exports it) and must have
# been configured (mdp's default_rack.cpp is generated at configure time); scripts/test.sh
# runs this on its release build. Environment: CLANG_TIDY (default clang-tidy), TIDY_JOBS
# (default 2).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${1:-build}
TIDY=${CLANG_TIDY:-clang-tidy}
JOBS=${TIDY_JOBS:-2}

if ! command -v "$TIDY" >/dev/null; then
  echo "tidy: $TIDY not found (Debian package clang-tidy)" >&2
  exit 2
fi
if [ ! -f "$BUILD/compile_commands.json" ]; then
  echo "tidy: $BUILD/compile_commands.json not found; configure the build first" >&2
  exit 2
fi

mapfile -t files < <(find base coe foe ecat mdp modules esi device apps -name '*.cpp' -type f | sort)
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
started=$(date +%s)

# One log and one exit code per file, so parallel output never interleaves and a crash or a
# compile error (which prints no check name) still fails the run.
export TIDY BUILD out
printf '%s\n' "${files[@]}" | xargs -P "$JOBS" -n 1 bash -c '
  f=$1; log="$out/$(printf %s "$f" | tr / _)"
  rc=0
  "$TIDY" -p "$BUILD" --config-file=.clang-tidy --quiet --warnings-as-errors="*" "$f" >"$log.txt" 2>&1 || rc=$?
  echo "$rc" >"$log.rc"
' _

# A header's finding shows up once per source including it: count it once.
cat "$out"/*.txt | grep -E '^[^ ].*:[0-9]+:[0-9]+: (warning|error): ' | sort -u >"$out/findings" || true
findings=$(wc -l <"$out/findings")
failed=0
for f in "${files[@]}"; do
  log="$out/$(printf %s "$f" | tr / _)"
  if [ "$(cat "$log.rc")" != 0 ]; then
    failed=$((failed + 1))
    # Show the full output (with the source excerpts) of every file that failed.
    grep -v -E '^[0-9]+ (warning|error)s? (generated|treated as errors?)\.?$' "$log.txt" || true
  fi
done

seconds=$(($(date +%s) - started))
echo "tidy: ${#files[@]} files, $findings findings, $failed files failing, ${seconds} s"
if [ "$findings" -ne 0 ] || [ "$failed" -ne 0 ]; then
  exit 1
fi
