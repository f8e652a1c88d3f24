# The C++ settings every Hapticut build shares (the repository's project and the evaluation's
# own, tools/evaluation/pyproject.toml): C++20, position-independent code, Release unless
# asked otherwise, -march=native when HAPTICUT_NATIVE is on and the compiler takes it.
set(CMAKE_CXX_STANDARD 20)
set(CMAKE_CXX_STANDARD_REQUIRED ON)
set(CMAKE_CXX_EXTENSIONS OFF)
set(CMAKE_EXPORT_COMPILE_COMMANDS ON)
set(CMAKE_POSITION_INDEPENDENT_CODE ON)
if(NOT CMAKE_BUILD_TYPE)
  set(CMAKE_BUILD_TYPE Release)
endif()

if(HAPTICUT_NATIVE)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag(-march=native HAPTICUT_HAS_MARCH_NATIVE)
  if(NOT HAPTICUT_HAS_MARCH_NATIVE)
    set(HAPTICUT_NATIVE OFF)
  endif()
endif()
