#!/usr/bin/env bash
# The test command (README.md): setup, lint, the C++ tests (plain and under ASan/UBSan), the
# scene reader fuzzer, the Python tests, the servo's tests under TSan.
set -euo pipefail
cd "$(dirname "$0")/.."
# Each phase prints its start time and the seconds since the run began (CI has 90 minutes).
phase() { echo "== $* [$(date -u +%H:%M:%S), +${SECONDS}s]"; }

phase "Setup"
bash tests/scripts/setup.sh
phase "Lint"
bash tests/scripts/lint.sh
phase "C++ tests (ctest)"
ctest --test-dir build/tests --output-on-failure -j 2 --timeout 300
phase "C++ tests under ASan and UBSan (ctest in build/asan)"
bash tests/scripts/sanitizers.sh run
phase "Scene reader fuzzing (libFuzzer, bounded time)"
bash tests/scripts/fuzz.sh
phase "Python tests (pytest)"
python3 -m pytest -q -m "not slow" tests/python --ignore=tests/python/addon
phase "Servo under ThreadSanitizer (its threads' tests, build/tsan)"
bash tests/scripts/tsan.sh run
# bpy in a pytest process of its own (it is not imported beside the other suites' modules).
phase "Blender add-on tests (bpy 5.0.1)"
python3 -m pytest -q -p no:cacheprovider tests/python/addon
bash tests/scripts/addon_oldest_blender.sh
phase "All passed"
