#!/usr/bin/env bash
# Builds the libFuzzer harnesses with Debian's clang (-fsanitize=fuzzer,address,undefined)
# and runs each for a bounded time; they must find nothing:
#   scene_reader_fuzz     the C++ scene reader, seeded with the example scenes and test data;
#   control_message_fuzz  the servo's control message parser, seeded with tests/fuzz/control/.
#   HAPTICUT_FUZZ_SECONDS (default 60, the test command's and CI's): how long to fuzz the
#   scene reader; the control parser gets half of it (HAPTICUT_FUZZ_SECONDS=10 for a quick
#   local run; tests/run_long_fuzz.sh is the long walk of the engine's invariants).
# Findings are written to build/fuzz/findings/; each one becomes a regression test
# (tests/cpp/scene_reader_limits_test.cpp, tests/python/test_servo_hostile_client.py).
set -euo pipefail
cd "$(dirname "$0")/../.."

seconds="${HAPTICUT_FUZZ_SECONDS:-60}"
out=build/fuzz
mkdir -p "$out/corpus" "$out/control-corpus" "$out/findings" "$out/obj"
flags=(-std=c++20 -O1 -g -fno-omit-frame-pointer -ffp-contract=off
  -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -Icore/include -Iserver)
# Through ccache when it is installed (a fresh clone then compiles nothing it compiled before).
compiler=(clang++)
if command -v ccache >/dev/null 2>&1; then
  compiler=(ccache clang++)
  # Not the folder: with -g ccache would hash it, and no other clone would hit.
  export CCACHE_BASEDIR="$PWD" CCACHE_NOHASHDIR=1
fi
# An object is rebuilt when its source, or any header, is newer than it.
newest_header=$(ls -t core/include/hapticut/*.h core/src/*.h server/*.h | head -1)
# Compiles the sources into build/fuzz/obj and links them into build/fuzz/NAME.
build_harness() {
  local name=$1
  shift
  local objects=() source object
  for source in "$@"; do
    object="$out/obj/$(basename "${source%.cpp}").o"
    objects+=("$object")
    if [ ! -f "$object" ] || [ "$source" -nt "$object" ] || [ "$newest_header" -nt "$object" ]; then
      echo "fuzz: clang++ $source"
      "${compiler[@]}" "${flags[@]}" -c "$source" -o "$object"
    fi
  done
  clang++ "${flags[@]}" "${objects[@]}" -o "$out/$name"
}
# Runs build/fuzz/NAME on CORPUS for SECONDS; fails with the log's tail on a finding.
run_harness() {
  local name=$1 corpus=$2 run_seconds=$3
  echo "fuzz: $name for ${run_seconds} s"
  # -max_len keeps inputs small enough for many runs per second; the large
  # example scenes still seed it through their first bytes.
  "$out/$name" "$corpus" -max_total_time="$run_seconds" -max_len=8192 -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$out/findings/$name-" \
    2>"$out/$name.log" || {
    tail -50 "$out/$name.log" >&2
    echo "fuzz: $name found a problem (above; input in $out/findings/)" >&2
    exit 1
  }
  grep -a -E '^stat::number_of_executed_units|^stat::average_exec_per_sec|^#[0-9]+.*DONE' \
    "$out/$name.log"
}

engine=(core/src/scene_io.cpp core/src/scene_reader.cpp core/src/scene_values.cpp
  core/src/scene_writer.cpp core/src/file_io.cpp core/src/scene_tree.cpp core/src/scene.cpp
  core/src/material_table.cpp core/src/parameter_range.cpp core/src/material.cpp
  core/src/space.cpp core/src/tet_mesh.cpp core/src/aabb_tree.cpp core/src/geometry.cpp)
build_harness scene_reader_fuzz "${engine[@]}" tests/fuzz/scene_reader_fuzz.cpp
build_harness control_message_fuzz "${engine[@]}" server/control_message.cpp \
  tests/fuzz/control_message_fuzz.cpp
cp examples/*.msgpack tests/data/*.json "$out/corpus/"
cp tests/fuzz/control/* "$out/control-corpus/"
run_harness scene_reader_fuzz "$out/corpus" "$seconds"
run_harness control_message_fuzz "$out/control-corpus" "$((seconds / 2))"
