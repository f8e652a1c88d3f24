# Installing Hapticut on a Debian machine, shared by the demo (examples/demo.sh: the product
# only) and the test command (tests/scripts/setup.sh: the product, its tests and the tools).
# Sourced, not run. Every step is skipped when what it installs is already there, so a second
# run installs nothing:
#   apt packages     dpkg says which are missing; only those are installed (as root);
#   the toolkit      one CMake build tree, build/main, serves the Python module, the servo and
#                    the C++ tests; a stamp (build/stamps/) records the sources' hash and the
#                    installed module's, so an unchanged tree is not packed and installed again;
#   bpy              pip is asked only when the interpreter lacks that exact version.

install_say() { echo "install: $*"; }

# The Debian packages among "$@" that are not installed, installed with apt (root only).
install_apt() {
  local missing=() package
  for package in "$@"; do
    dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" -ne 0 ]; then
    echo "install: missing Debian packages (${missing[*]}); run as root or install them" >&2
    return 1
  fi
  install_say "apt-get install ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
}

# What the product's build needs from Debian: the compiler and CMake, nlohmann's JSON (the
# scene reader), hidapi through pkg-config (the HID devices).
PRODUCT_APT_PACKAGES=(cmake ninja-build g++ nlohmann-json3-dev pkg-config libhidapi-dev)

# The PyPI packages the build itself imports (the toolkit builds without isolation, so that
# its build tree stays valid from one run to the next).
install_build_tools() {
  if python3 -c "import numpy, scikit_build_core, nanobind" >/dev/null 2>&1; then
    return 0
  fi
  install_say "pip install numpy scikit-build-core nanobind"
  python3 -m pip install -q --disable-pip-version-check "numpy>=1.26,<2" \
    "scikit-build-core>=0.10" "nanobind>=2.4"
}

# A hash of the files under the given paths (tracked or not, ignored ones aside) and of the
# extra words, so that any edit, commit or option changes it.
sources_hash() {
  local words=$1
  shift
  {
    echo "$words"
    # Sorted: git lists tracked files before untracked ones, and a commit must not count.
    git ls-files -z --cached --others --exclude-standard -- "$@" | sort -zu |
      xargs -0 -r sha1sum 2>/dev/null
  } | sha1sum | cut -d' ' -f1
}

# The hash of an installed module's file (import name in $1), "" when it does not import.
installed_hash() {
  local file
  file=$(python3 -c "import $1 as m; print(m.__file__)" 2>/dev/null | tail -n 1) || return 0
  [ -f "$file" ] && sha1sum "$file" | cut -d' ' -f1
}

# The compiler cache, when ccache is installed (tests/scripts/setup.sh installs it): every
# build of the test command (build/main through pip, the sanitizer builds, the fuzzers)
# compiles through it, so a fresh clone on a machine that built the same sources before
# compiles nothing again. Paths under the checkout are hashed relative to it (CCACHE_BASEDIR),
# so two clones share their objects; debug info then names the first clone's folder.
CMAKE_LAUNCHER_DEFINES=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
  CMAKE_LAUNCHER_DEFINES=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi

stamp_matches() { [ -f "build/stamps/$1" ] && [ "$(cat "build/stamps/$1")" = "$2" ]; }
stamp_write() { mkdir -p build/stamps && echo "$2" >"build/stamps/$1"; }

# The toolkit (hapticut, its module _core and the servo) from this checkout, built in
# build/main for this CPU. "tests" also builds the C++ tests in the same tree and installs the
# test extras; the product's own stamp is then satisfied too (a superset was built).
TOOLKIT_SOURCES=(VERSION core server cmake CMakeLists.txt pyproject.toml examples tests/cpp
  tools/evaluation/src tools/evaluation/include tools/evaluation/tests
  tools/evaluation/CMakeLists.txt)
install_toolkit() {
  local with_tests=${1:-} name=toolkit extras="build" tests_flag=OFF
  if [ "$with_tests" = tests ]; then
    name=toolkit-tests extras="build,test" tests_flag=ON
  fi
  local key
  key=$(sources_hash "$(command -v python3) $extras" "${TOOLKIT_SOURCES[@]}")
  if stamp_matches "$name" "$key $(installed_hash hapticut._core)"; then
    install_say "the toolkit is installed from these sources (build/main)"
    return 0
  fi
  install_build_tools
  install_say "pip install .[$extras] (builds hapticut._core, hapticut-servo$([ "$tests_flag" = ON ] &&
    echo ", the C++ tests") in build/main)"
  # Tuned for this machine (-march=native): the demo, tests, benchmarks and evaluation run
  # where they are built. Wheels for elsewhere are built without it.
  local launcher=()
  [ ${#CMAKE_LAUNCHER_DEFINES[@]} -eq 0 ] || launcher=(-C cmake.define.CMAKE_CXX_COMPILER_LAUNCHER=ccache)
  python3 -m pip install -q --disable-pip-version-check --no-build-isolation \
    -C build-dir="$PWD/build/main" -C cmake.define.HAPTICUT_NATIVE=ON "${launcher[@]}" \
    -C cmake.define.HAPTICUT_BUILD_TESTS="$tests_flag" ".[$extras]"
  stamp_write "$name" "$key $(installed_hash hapticut._core)"
  if [ "$tests_flag" = ON ]; then
    key=$(sources_hash "$(command -v python3) build" "${TOOLKIT_SOURCES[@]}")
    stamp_write toolkit "$key $(installed_hash hapticut._core)"
  fi
}

# bpy (Blender as a Python module, about 370 MB) at version $1 for the interpreter $2.
install_bpy() {
  local version=$1 python=${2:-python3}
  local found
  found=$("$python" -c "import bpy; print('.'.join(map(str, bpy.app.version)))" 2>/dev/null |
    tail -n 1) || true
  if [ "$found" = "$version" ]; then
    return 0
  fi
  install_say "pip install bpy==$version ($python)"
  "$python" -m pip install -q --disable-pip-version-check "bpy==$version"
}
