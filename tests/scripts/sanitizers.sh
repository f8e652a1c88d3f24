#!/usr/bin/env bash
# The C++ tests built with AddressSanitizer and UndefinedBehaviorSanitizer in
# their own build directory (build/asan): `build` configures and compiles
# (tests/scripts/setup.sh calls it), `run` runs them with ctest and fails on
# any report (tests/run_all.sh calls it).
#
# Filter: none. Every C++ test runs under the sanitizers at its default size
# (the invariant fuzz runs its default steps; only tests/run_long_fuzz.sh's
# 10^7-step variant is left to the plain build).
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/install_lib.sh  # CMAKE_LAUNCHER_DEFINES: ccache, when installed

case "${1:-run}" in
  build)
    cmake -S . -B build/asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      "${CMAKE_LAUNCHER_DEFINES[@]}" \
      -DHAPTICUT_BUILD_TESTS=ON -DHAPTICUT_BUILD_PYTHON=OFF \
      -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all" \
      -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
    cmake --build build/asan -j 2
    ;;
  run)
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
      UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      ctest --test-dir build/asan --output-on-failure -j 2 --timeout 600
    ;;
  *)
    echo "usage: $0 [build|run]" >&2
    exit 2
    ;;
esac
