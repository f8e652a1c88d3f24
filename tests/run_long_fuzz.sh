#!/usr/bin/env bash
# The long invariant run (not part of the test command): 10^7 steps per
# scenario by default; HAPTICUT_FUZZ_STEPS=N sets another count. The walks
# include segments q -> p exactly through boundary vertices, edges and faces
# and along face planes, and check after every tick that the invariants hold
# (an OUTSIDE q outside the mesh among them) and that stepping again with the
# same p changes nothing (tests/cpp/invariants_fuzz_test.cpp).
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x build/main/tests/cpp/hapticut_tests ] || bash tests/scripts/setup.sh
HAPTICUT_FUZZ_STEPS="${HAPTICUT_FUZZ_STEPS:-10000000}" \
  build/main/tests/cpp/hapticut_tests --gtest_filter='Invariants.*'
