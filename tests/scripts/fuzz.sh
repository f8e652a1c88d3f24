#!/usr/bin/env bash
# Builds the libFuzzer harness of the C++ scene reader with Debian's clang
# (-fsanitize=fuzzer,address,undefined) and runs it for a bounded time,
# seeded with the example scenes and the test data; it must find nothing.
#   HAPTICUT_FUZZ_SECONDS (default 60): how long to fuzz.
# Findings are written to build/fuzz/findings/; each one becomes a
# regression test (tests/cpp/scene_reader_limits_test.cpp).
set -euo pipefail
cd "$(dirname "$0")/../.."

seconds="${HAPTICUT_FUZZ_SECONDS:-60}"
out=build/fuzz
mkdir -p "$out/corpus" "$out/findings" "$out/obj"
sources=(core/src/scene_io.cpp core/src/scene_reader.cpp core/src/scene_values.cpp
  core/src/scene_writer.cpp core/src/file_io.cpp core/src/scene_tree.cpp core/src/scene.cpp
  core/src/material_table.cpp core/src/parameter_range.cpp core/src/material.cpp
  core/src/space.cpp core/src/tet_mesh.cpp core/src/aabb_tree.cpp core/src/geometry.cpp
  tests/fuzz/scene_reader_fuzz.cpp)
flags=(-std=c++20 -O1 -g -fno-omit-frame-pointer -ffp-contract=off
  -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -Icore/include)
binary="$out/scene_reader_fuzz"
# An object is rebuilt when its source, or any header, is newer than it.
newest_header=$(ls -t core/include/hapticut/*.h core/src/*.h | head -1)
objects=()
for source in "${sources[@]}"; do
  object="$out/obj/$(basename "${source%.cpp}").o"
  objects+=("$object")
  if [ ! -f "$object" ] || [ "$source" -nt "$object" ] || [ "$newest_header" -nt "$object" ]; then
    echo "fuzz: clang++ $source"
    clang++ "${flags[@]}" -c "$source" -o "$object"
  fi
done
clang++ "${flags[@]}" "${objects[@]}" -o "$binary"
cp examples/*.msgpack tests/data/*.json "$out/corpus/"
echo "fuzz: scene reader for ${seconds} s"
# -max_len keeps inputs small enough for many runs per second; the large
# example scenes still seed it through their first bytes.
"$binary" "$out/corpus" -max_total_time="$seconds" -max_len=8192 -timeout=10 \
  -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$out/findings/" 2>"$out/fuzz.log" || {
  tail -50 "$out/fuzz.log" >&2
  echo "fuzz: the scene reader fuzzer found a problem (above; input in $out/findings/)" >&2
  exit 1
}
grep -a -E '^stat::number_of_executed_units|^stat::average_exec_per_sec|^#[0-9]+.*DONE' "$out/fuzz.log"
