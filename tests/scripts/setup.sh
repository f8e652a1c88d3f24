#!/usr/bin/env bash
# Installs everything the tests, the benchmarks and the demo need on a fresh
# Debian machine (apt packages when run as root, PyPI packages), then builds:
# the Python package with its C++ module (pip) and the C++ test binary (CMake).
set -euo pipefail
cd "$(dirname "$0")/../.."

# clang and its runtime libraries: the scene reader's libFuzzer harness (tests/scripts/fuzz.sh);
# hidapi (through pkg-config): the HID devices.
apt_packages=(cmake ninja-build g++ nlohmann-json3-dev libgtest-dev clang-format clang-tidy clang
  libclang-rt-14-dev pkg-config libhidapi-dev)
missing=()
for package in "${apt_packages[@]}"; do
  dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" -ne 0 ]; then
    echo "setup: missing Debian packages (${missing[*]}); run as root or install them" >&2
    exit 1
  fi
  echo "setup: apt-get install ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
fi

python3 -m pip install -q --disable-pip-version-check "numpy>=1.26,<2" "scikit-build-core>=0.10" "nanobind>=2.4"
echo "setup: pip install .[build,test] (builds hapticut._core)"
# Tuned for this machine (-march=native): the tests, benchmarks and evaluation
# run where they are built. Wheels for elsewhere are built without it.
python3 -m pip install -q --disable-pip-version-check -C cmake.define.HAPTICUT_NATIVE=ON \
  ".[build,test]"
# The evaluation (tools/evaluation, not in the product's wheel): its package and its
# module hapticut_evaluation._baselines, built beside its own copy of the engine (and
# matplotlib for its charts).
echo "setup: pip install ./tools/evaluation (builds hapticut_evaluation._baselines)"
python3 -m pip install -q --disable-pip-version-check -C cmake.define.HAPTICUT_NATIVE=ON \
  ./tools/evaluation

# The add-on's tests run inside Blender's Python module (about 370 MB), and once more under
# the oldest Blender the manifest admits (bpy 4.2.0) in a virtual environment of its own.
echo "setup: pip install bpy==5.0.1 (the add-on's tests)"
python3 -m pip install -q --disable-pip-version-check "bpy==5.0.1"
if [ ! -x build/venv-bpy42/bin/python ]; then
  python3 -m venv --system-site-packages build/venv-bpy42
fi
echo "setup: pip install bpy==4.2.0 into build/venv-bpy42"
build/venv-bpy42/bin/python -m pip install -q --disable-pip-version-check "bpy==4.2.0" pytest pytest-timeout

echo "setup: building the C++ tests"
cmake -S . -B build/tests -G Ninja -DCMAKE_BUILD_TYPE=Release -DHAPTICUT_BUILD_TESTS=ON \
  -DHAPTICUT_BUILD_PYTHON=OFF -DHAPTICUT_NATIVE=ON >/dev/null
cmake --build build/tests

echo "setup: building the C++ tests with AddressSanitizer and UndefinedBehaviorSanitizer (build/asan)"
bash tests/scripts/sanitizers.sh build

echo "setup: building the servo with ThreadSanitizer (build/tsan)"
bash tests/scripts/tsan.sh build
