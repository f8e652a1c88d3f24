#!/usr/bin/env bash
# The long invariant run (not part of the test command): 10^7 steps per
# scenario by default; HAPTICUT_FUZZ_STEPS=N sets another count.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x build/tests/tests/cpp/hapticut_tests ] || bash tests/scripts/setup.sh
HAPTICUT_FUZZ_STEPS="${HAPTICUT_FUZZ_STEPS:-10000000}" \
  build/tests/tests/cpp/hapticut_tests --gtest_filter='Invariants.*'
