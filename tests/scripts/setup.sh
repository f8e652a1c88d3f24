#!/usr/bin/env bash
# Installs and builds everything the tests, the benchmarks and the evaluation need on a Debian
# machine (tools/install_lib.sh: each step is skipped when it is already done):
#   build/main   the toolkit (Python module, servo) and the C++ tests: one CMake build tree;
#   build/evaluation  the evaluation's module, linked against build/main's engine;
#   build/asan, build/tsan  the sanitizer builds (their own flags: compiled again);
#   bpy 5.0.1, and bpy 4.2.0 in build/venv-bpy42 (the add-on's oldest Blender).
set -euo pipefail
cd "$(dirname "$0")/../.."
source tools/install_lib.sh

# The product's packages, then the tests' (GoogleTest, the linters, clang with its runtime
# libraries for the fuzzers and ThreadSanitizer, ccache for every build below).
install_apt "${PRODUCT_APT_PACKAGES[@]}" libgtest-dev clang-format clang-tidy clang \
  libclang-rt-14-dev ccache
# Sourced again now that ccache is there: the builds below compile through it.
source tools/install_lib.sh
install_toolkit tests

# The evaluation (tools/evaluation, not in the product's wheel): its package and its module
# hapticut_evaluation._baselines, linked against the engine build/main already compiled (and
# matplotlib for its charts).
key=$(sources_hash "$(command -v python3)" "${TOOLKIT_SOURCES[@]}" tools/evaluation)
if stamp_matches evaluation "$key $(installed_hash hapticut_evaluation._baselines)"; then
  install_say "the evaluation is installed from these sources (build/evaluation)"
else
  install_say "pip install ./tools/evaluation (hapticut_evaluation._baselines, linked to build/main)"
  launcher=()
  [ ${#CMAKE_LAUNCHER_DEFINES[@]} -eq 0 ] || launcher=(-C cmake.define.CMAKE_CXX_COMPILER_LAUNCHER=ccache)
  python3 -m pip install -q --disable-pip-version-check --no-build-isolation \
    -C build-dir="$PWD/build/evaluation" -C cmake.define.HAPTICUT_NATIVE=ON "${launcher[@]}" \
    -C cmake.define.HAPTICUT_ENGINE_BUILD_DIR="$PWD/build/main" ./tools/evaluation
  stamp_write evaluation "$key $(installed_hash hapticut_evaluation._baselines)"
fi

# The add-on's tests run inside Blender's Python module, and once more under the oldest
# Blender the manifest admits (bpy 4.2.0) in a virtual environment of its own.
install_bpy 5.0.1
if [ ! -x build/venv-bpy42/bin/python ]; then
  python3 -m venv --system-site-packages build/venv-bpy42
fi
install_bpy 4.2.0 build/venv-bpy42/bin/python
if ! build/venv-bpy42/bin/python -c "import pytest, pytest_timeout" >/dev/null 2>&1; then
  build/venv-bpy42/bin/python -m pip install -q --disable-pip-version-check pytest pytest-timeout
fi

# Ninja rebuilds only what changed; an up-to-date tree costs a second each.
install_say "the C++ tests under AddressSanitizer and UndefinedBehaviorSanitizer (build/asan)"
bash tests/scripts/sanitizers.sh build
install_say "the servo under ThreadSanitizer (build/tsan)"
bash tests/scripts/tsan.sh build
