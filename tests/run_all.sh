#!/usr/bin/env bash
# The test command (README.md): setup, lint, the C++ tests (plain and under ASan/UBSan), the
# fuzzers, the Python tests, the servo's tests under TSan, the add-on under two Blenders.
# Settings (environment): HAPTICUT_FUZZ_SECONDS (default 60, tests/scripts/fuzz.sh),
# HAPTICUT_TEST_WORKERS (pytest-xdist workers; default: the number of cores, 0: one process).
set -euo pipefail
cd "$(dirname "$0")/.."
# Each phase prints its start time and the seconds since the run began; at the end, or where
# a phase fails, a table of the phases' durations beside the targets (printed, not asserted).
phase_names=()
phase_starts=()
phase() {
  echo "== $* [$(date -u +%H:%M:%S), +${SECONDS}s]"
  phase_names+=("$*")
  phase_starts+=("$SECONDS")
}
phase_table() {
  local status=$? i end
  echo "== Phase times (s)"
  for i in "${!phase_names[@]}"; do
    end=${phase_starts[$((i + 1))]:-$SECONDS}
    printf '%6d  %s\n' "$((end - phase_starts[i]))" "${phase_names[i]}"
  done
  printf '%6d  total (%d min %02d s); targets on a 2-core machine: a first run under 20 min, a second under 10\n' \
    "$SECONDS" "$((SECONDS / 60))" "$((SECONDS % 60))"
  [ "$status" -eq 0 ] || echo "== Failed in: ${phase_names[-1]}" >&2
}
trap phase_table EXIT

phase "Setup (installs and builds what is missing or changed)"
bash tests/scripts/setup.sh
phase "Lint"
bash tests/scripts/lint.sh
phase "C++ tests (ctest in build/main)"
ctest --test-dir build/main --output-on-failure -j 2 --timeout 300
phase "C++ tests under ASan and UBSan (ctest in build/asan)"
bash tests/scripts/sanitizers.sh run
phase "Fuzzing the scene reader and the control parser (libFuzzer, bounded time)"
bash tests/scripts/fuzz.sh
# The Python tests in two runs: those that time no servo in parallel, one pytest-xdist worker
# per core (HAPTICUT_TEST_WORKERS); then the suites that time a real servo's threads (marker
# "serial") alone, so no other test's load decides their timing.
phase "Python tests in parallel (pytest -n ${HAPTICUT_TEST_WORKERS:-$(nproc)})"
python3 -m pytest -q -m "not slow and not serial" -n "${HAPTICUT_TEST_WORKERS:-$(nproc)}" \
  --dist loadgroup tests/python --ignore=tests/python/addon
phase "Python tests that time a real servo (pytest, serial)"
python3 -m pytest -q -m "not slow and serial" tests/python --ignore=tests/python/addon
phase "Servo under ThreadSanitizer (its threads' tests, build/tsan)"
bash tests/scripts/tsan.sh run
# bpy in a pytest process of its own (it is not imported beside the other suites' modules).
phase "Blender add-on tests (bpy 5.0.1, then 4.2.0)"
python3 -m pytest -q -p no:cacheprovider tests/python/addon
bash tests/scripts/addon_oldest_blender.sh
phase "All passed"
