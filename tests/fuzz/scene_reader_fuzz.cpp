// libFuzzer harness for the C++ scene reader. Every input
// is read in both encodings; the only exception allowed out of the reader is
// SceneError, and a scene it accepts must build a Space or be refused with
// MeshError / std::invalid_argument. Anything else (a crash, a sanitizer
// report, another exception, a hang) is a finding. Built and run for a
// bounded time by tests/scripts/fuzz.sh (part of the test command).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "hapticut/scene_io.h"
#include "hapticut/space.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::uint8_t> bytes(data, data + size);
  for (const auto encoding :
       {hapticut::SceneEncoding::Json, hapticut::SceneEncoding::MessagePack}) {
    hapticut::SceneDocument document;
    try {
      document = hapticut::parse_scene_document(bytes, encoding);
    } catch (const hapticut::SceneError&) {
      continue;
    }
    try {
      const auto space = hapticut::Space::from_scene(document.scene);
      (void)space;
    } catch (const hapticut::MeshError&) {
    } catch (const std::invalid_argument&) {
    }
    // What was read must write (the writer re-checks) and read back.
    const auto written = hapticut::serialize_scene_document(document, encoding);
    (void)hapticut::parse_scene_document(written, encoding);
  }
  return 0;
}
