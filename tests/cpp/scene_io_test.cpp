#include "hapticut/scene_io.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hapticut/reference_meshes.h"

namespace hapticut {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

#ifndef HAPTICUT_TEST_DATA_DIR
#define HAPTICUT_TEST_DATA_DIR "tests/data"
#endif

const std::string kDataDir = HAPTICUT_TEST_DATA_DIR;
const std::string kExamplePath = kDataDir + "/two_tets.hapticut.json";

std::vector<std::uint8_t> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

Json example_tree() { return Json::parse(file_bytes(kExamplePath)); }

std::vector<std::uint8_t> encode(const Json& tree, SceneEncoding encoding) {
  if (encoding == SceneEncoding::MessagePack) return Json::to_msgpack(tree);
  const std::string text = tree.dump();
  return {text.begin(), text.end()};
}

// The SceneError message of `read`, or "no error".
std::string error_of(const std::function<void()>& read) {
  try {
    read();
  } catch (const SceneError& error) {
    return error.what();
  }
  return "no error";
}

std::string parse_error(const Json& tree, SceneEncoding encoding, bool strict = false) {
  return error_of([&] { parse_scene(encode(tree, encoding), encoding, {.strict = strict}); });
}

void expect_same_scene(const Scene& a, const Scene& b) {
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (std::size_t i = 0; i < a.materials.size(); ++i) {
    EXPECT_EQ(a.materials[i].name, b.materials[i].name);
    EXPECT_EQ(a.materials[i].model, b.materials[i].model);
    EXPECT_EQ(a.materials[i].drag_distance_mm, b.materials[i].drag_distance_mm);
    EXPECT_EQ(a.materials[i].viscosity_N_s_per_mm, b.materials[i].viscosity_N_s_per_mm);
    EXPECT_EQ(a.materials[i].max_lag_mm, b.materials[i].max_lag_mm);
    EXPECT_EQ(a.materials[i].break_force_N, b.materials[i].break_force_N);
  }
  EXPECT_EQ(a.vertices_mm, b.vertices_mm);
  EXPECT_EQ(a.tets, b.tets);
  EXPECT_EQ(a.tet_materials, b.tet_materials);
  ASSERT_EQ(a.blades.size(), b.blades.size());
  for (std::size_t i = 0; i < a.blades.size(); ++i) {
    EXPECT_EQ(a.blades[i].name, b.blades[i].name);
    EXPECT_EQ(a.blades[i].start_mm, b.blades[i].start_mm);
    EXPECT_EQ(a.blades[i].end_mm, b.blades[i].end_mm);
    EXPECT_EQ(a.blades[i].points, b.blades[i].points);
    EXPECT_EQ(a.blades[i].coupling, b.blades[i].coupling);
    EXPECT_EQ(a.blades[i].orientation, b.blades[i].orientation);
  }
  EXPECT_EQ(a.stiffness_N_per_mm, b.stiffness_N_per_mm);
  EXPECT_EQ(a.servo_rate_Hz, b.servo_rate_Hz);
  EXPECT_EQ(a.tolerance_mm, b.tolerance_mm);
  EXPECT_EQ(a.max_transitions_per_tick, b.max_transitions_per_tick);
  EXPECT_EQ(a.safety.max_force_N, b.safety.max_force_N);
  EXPECT_EQ(a.safety.max_torque_N_mm, b.safety.max_torque_N_mm);
  EXPECT_EQ(a.safety.ramp_time_s, b.safety.ramp_time_s);
  EXPECT_EQ(a.safety.capped_tick_force_N, b.safety.capped_tick_force_N);
}

// A fresh, empty directory for one test's files.
fs::path scratch_directory(const std::string& name) {
  fs::path directory = fs::temp_directory_path() / ("hapticut_scene_io_test_" + name);
  fs::remove_all(directory);
  fs::create_directories(directory);
  return directory;
}

std::vector<std::string> file_names(const fs::path& directory) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory)) {
    names.push_back(entry.path().filename().string());
  }
  return names;
}

// --- Reading -------------------------------------------------------------------------------

TEST(SceneIo, ExampleFileReadsWithEveryField) {
  const SceneDocument document = load_scene_document(kExamplePath);
  const Scene& scene = document.scene;
  ASSERT_EQ(scene.materials.size(), 2u);
  EXPECT_EQ(scene.materials[1].name, "flesh");
  EXPECT_EQ(scene.materials[1].model, MaterialModel::Drag);
  EXPECT_EQ(scene.materials[1].drag_distance_mm, 1.0);
  EXPECT_EQ(scene.vertices_mm.size(), 5u);
  EXPECT_EQ(scene.vertices_mm[4], Vec3(10, 10, 10));
  ASSERT_EQ(scene.tets.size(), 2u);
  EXPECT_EQ(scene.tets[1], (std::array<std::int32_t, 4>{1, 2, 3, 4}));
  EXPECT_EQ(scene.tet_materials, (std::vector<std::int32_t>{1, 0}));
  ASSERT_EQ(scene.blades.size(), 1u);
  EXPECT_EQ(scene.blades[0].end_mm, Vec3(100, 0, 0));
  EXPECT_EQ(scene.blades[0].points, 50);
  // The file names neither: a rigid blade with its own orientation, the defaults.
  EXPECT_EQ(scene.blades[0].coupling, BladeCoupling::Rigid);
  EXPECT_EQ(scene.blades[0].orientation, BladeOrientation::Free);
  EXPECT_EQ(scene.stiffness_N_per_mm, 0.1);
  EXPECT_EQ(scene.servo_rate_Hz, 1000.0);
  EXPECT_EQ(document.reoriented_tets, 0);
  EXPECT_NE(document.metadata_json.find("description"), std::string::npos);
}

TEST(SceneIo, OptionalSectionsTakeTheirDefaults) {
  Json tree = example_tree();
  for (const char* key : {"coupling", "tolerance_mm", "blades", "metadata"}) tree.erase(key);
  const SceneDocument document =
      parse_scene_document(encode(tree, SceneEncoding::Json), SceneEncoding::Json);
  const Scene defaults;
  EXPECT_TRUE(document.scene.blades.empty());
  EXPECT_EQ(document.metadata_json, "{}");
  EXPECT_EQ(document.scene.stiffness_N_per_mm, defaults.stiffness_N_per_mm);
  EXPECT_EQ(document.scene.max_transitions_per_tick, defaults.max_transitions_per_tick);
}

TEST(SceneIo, EveryModelReadsWithItsParameters) {
  Json tree = example_tree();
  tree["materials"].push_back({{"name", "bone"}, {"model", "rigid"}});
  tree["materials"].push_back(
      {{"name", "fluid"}, {"model", "viscous"}, {"viscosity_N_s_per_mm", 0.001}});
  tree["materials"].push_back({{"name", "skin"}, {"model", "membrane"}, {"break_force_N", 1.0}});
  const Scene scene = parse_scene(encode(tree, SceneEncoding::Json), SceneEncoding::Json);
  EXPECT_EQ(scene.materials[2].model, MaterialModel::Rigid);
  EXPECT_EQ(scene.materials[3].viscosity_N_s_per_mm, 0.001);
  EXPECT_EQ(scene.materials[3].max_lag_mm, 50.0);
  EXPECT_EQ(scene.materials[4].break_force_N, 1.0);
}

TEST(SceneIo, ModelNamesRoundTrip) {
  for (MaterialModel model : {MaterialModel::Free, MaterialModel::Drag, MaterialModel::Rigid,
                              MaterialModel::Viscous, MaterialModel::Membrane}) {
    EXPECT_EQ(material_model_from_name(material_model_name(model)), model);
  }
  EXPECT_FALSE(material_model_from_name("jelly").has_value());
}

TEST(SceneIo, BladeSettingNamesRoundTrip) {
  for (BladeCoupling coupling : {BladeCoupling::Rigid, BladeCoupling::Independent}) {
    EXPECT_EQ(blade_coupling_from_name(blade_coupling_name(coupling)), coupling);
  }
  for (BladeOrientation orientation : {BladeOrientation::Free, BladeOrientation::Locked}) {
    EXPECT_EQ(blade_orientation_from_name(blade_orientation_name(orientation)), orientation);
  }
  EXPECT_FALSE(blade_coupling_from_name("Rigid").has_value());
  EXPECT_FALSE(blade_orientation_from_name("").has_value());
}

TEST(SceneIo, BladeCouplingAndOrientationRoundTripInBothEncodings) {
  Scene scene = load_scene(kExamplePath);
  scene.blades[0].coupling = BladeCoupling::Independent;
  scene.blades.push_back({"chisel", {0, 0, 0}, {0, 0, 20}, 9});
  scene.blades[1].orientation = BladeOrientation::Locked;
  for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
    const Scene again = parse_scene(serialize_scene(scene, encoding), encoding);
    expect_same_scene(again, scene);
    EXPECT_EQ(again.blades[0].coupling, BladeCoupling::Independent);
    EXPECT_EQ(again.blades[1].coupling, BladeCoupling::Rigid);
    EXPECT_EQ(again.blades[1].orientation, BladeOrientation::Locked);
  }
  const auto json = serialize_scene(scene, SceneEncoding::Json);
  const std::string text(json.begin(), json.end());
  EXPECT_NE(text.find(R"("coupling": "independent")"), std::string::npos);
  EXPECT_NE(text.find(R"("orientation": "locked")"), std::string::npos);
}

TEST(SceneIo, EncodingFollowsTheFileName) {
  EXPECT_EQ(encoding_for_path("a.hapticut.msgpack"), SceneEncoding::MessagePack);
  EXPECT_EQ(encoding_for_path("a.hapticut.json"), SceneEncoding::Json);
  EXPECT_EQ(encoding_for_path("msgpack"), SceneEncoding::Json);
}

// --- Bad inputs: one table shared with tests/python/test_scene_format.py -------------------

TEST(SceneIo, EveryBadInputNamesFieldAndReason) {
  const Json cases = Json::parse(file_bytes(kDataDir + "/scene_error_cases.json"))["cases"];
  ASSERT_GT(cases.size(), 40u);
  for (const Json& bad : cases) {
    const Json tree = example_tree().patch(bad["patch"]);
    const bool strict = bad.value("strict", false);
    for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
      SCOPED_TRACE(bad["name"].get<std::string>() +
                   (encoding == SceneEncoding::Json ? " (JSON)" : " (MessagePack)"));
      EXPECT_EQ(parse_error(tree, encoding, strict), bad["error"].get<std::string>());
    }
  }
}

TEST(SceneIo, ErrorCarriesTheField) {
  Json tree = example_tree();
  tree["mesh"]["tets"][1][3] = 99;
  try {
    parse_scene(encode(tree, SceneEncoding::Json), SceneEncoding::Json);
    FAIL() << "no error";
  } catch (const SceneError& error) {
    EXPECT_EQ(error.field(), "/mesh/tets/1/3");
    EXPECT_STREQ(error.what(), "/mesh/tets/1/3: vertex index 99 out of range (5 vertices)");
  }
}

TEST(SceneIo, TruncatedFile) {
  const Scene scene = load_scene(kExamplePath);
  for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
    const std::vector<std::uint8_t> bytes = serialize_scene(scene, encoding);
    const std::string expected = encoding == SceneEncoding::Json
                                     ? "(root): truncated or not valid JSON: "
                                     : "(root): truncated or not valid MessagePack: ";
    for (double fraction : {0.0, 0.3, 0.5, 0.99}) {
      const std::vector<std::uint8_t> prefix(
          bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(bytes.size() * fraction));
      const std::string message = error_of([&] { parse_scene(prefix, encoding); });
      EXPECT_EQ(message.rfind(expected, 0), 0u) << message;
    }
  }
}

TEST(SceneIo, NonFiniteCoordinateInMessagePack) {
  for (double value : {std::nan(""), std::numeric_limits<double>::infinity()}) {
    Json tree = example_tree();
    tree["mesh"]["vertices"][3][1] = value;
    EXPECT_EQ(parse_error(tree, SceneEncoding::MessagePack),
              "/mesh/vertices/3/1: not a finite number");
  }
}

// JSON has no NaN literal; Python's json writes one anyway. The C++ parser
// rejects the text, at the offending position (the Python reader names the field).
TEST(SceneIo, NanLiteralInJsonText) {
  std::string text = example_tree().dump();
  const std::string vertex = "[0,0,10]";
  text.replace(text.find(vertex), vertex.size(), "[0,NaN,10]");
  const std::string message = error_of([&] {
    parse_scene({text.begin(), text.end()}, SceneEncoding::Json);
  });
  EXPECT_EQ(message.rfind("(root): truncated or not valid JSON: ", 0), 0u) << message;
  EXPECT_NE(message.find("column"), std::string::npos) << message;
}

TEST(SceneIo, InvertedTetIsReorientedByDefaultAndRejectedWhenStrict) {
  Json tree = example_tree();
  tree["mesh"]["tets"][1] = {2, 1, 3, 4};
  const auto bytes = encode(tree, SceneEncoding::Json);
  const SceneDocument document = parse_scene_document(bytes, SceneEncoding::Json);
  EXPECT_EQ(document.reoriented_tets, 1);
  EXPECT_EQ(document.scene.tets[1], (std::array<std::int32_t, 4>{2, 1, 4, 3}));
  EXPECT_EQ(error_of([&] { parse_scene(bytes, SceneEncoding::Json, {.strict = true}); }),
            "/mesh/tets/1: inverted (negative volume)");
}

TEST(SceneIo, IntegralFloatsCountAsIntegers) {
  Json tree = example_tree();
  tree["mesh"]["tets"][1] = {1.0, 2.0, 3.0, 4.0};
  const Scene scene = parse_scene(encode(tree, SceneEncoding::Json), SceneEncoding::Json);
  EXPECT_EQ(scene.tets[1], (std::array<std::int32_t, 4>{1, 2, 3, 4}));
}

// --- Writing -------------------------------------------------------------------------------

TEST(SceneIo, RoundTripInBothEncodings) {
  const SceneDocument original = load_scene_document(kExamplePath);
  for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
    const SceneDocument again =
        parse_scene_document(serialize_scene_document(original, encoding), encoding);
    expect_same_scene(again.scene, original.scene);
    EXPECT_EQ(again.metadata_json, original.metadata_json);
  }
}

TEST(SceneIo, JsonToMessagePackToJsonIsByteIdentical) {
  const SceneDocument original = load_scene_document(kExamplePath);
  const auto json_bytes = serialize_scene_document(original, SceneEncoding::Json);
  const auto via_msgpack = parse_scene_document(
      serialize_scene_document(parse_scene_document(json_bytes, SceneEncoding::Json),
                               SceneEncoding::MessagePack),
      SceneEncoding::MessagePack);
  EXPECT_EQ(serialize_scene_document(via_msgpack, SceneEncoding::Json), json_bytes);
}

TEST(SceneIo, RoundTripKeepsExactDoubles) {
  Scene scene = load_scene(kExamplePath);
  scene.vertices_mm[4] = {10.0 + 0.1 + 0.2, 10.0 / 3.0 + 7.0, 10.0 + 1e-12};
  scene.blades[0].start_mm = {-2e20, 5e-324, 1e-300};
  scene.blades[0].end_mm = {123456.789, 1.0 / 3.0, 0.1 + 0.2};
  for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
    expect_same_scene(parse_scene(serialize_scene(scene, encoding), encoding), scene);
  }
}

TEST(SceneIo, WriterChecksTheSceneLikeTheReader) {
  Scene scene = load_scene(kExamplePath);
  scene.vertices_mm[0].x = std::nan("");
  EXPECT_EQ(error_of([&] { serialize_scene(scene, SceneEncoding::Json); }),
            "/mesh/vertices/0/0: not a finite number");
  scene = load_scene(kExamplePath);
  scene.tet_materials[0] = 5;
  EXPECT_EQ(error_of([&] { serialize_scene(scene, SceneEncoding::MessagePack); }),
            "/mesh/tet_materials/0: unknown material 5 (2 materials)");
  SceneDocument document;
  document.scene = load_scene(kExamplePath);
  document.metadata_json = "[1]";
  EXPECT_EQ(error_of([&] { serialize_scene_document(document, SceneEncoding::Json); }),
            "/metadata: expected an object, got array");
}

TEST(SceneIo, SaveIsAtomic) {
  const fs::path directory = scratch_directory("atomic");
  const std::string path = (directory / "scene.hapticut.json").string();
  const Scene scene = load_scene(kExamplePath);
  save_scene(scene, path);
  const auto before = file_bytes(path);
  EXPECT_EQ(file_names(directory), std::vector<std::string>{"scene.hapticut.json"});

  Scene invalid = scene;
  invalid.materials.clear();
  EXPECT_EQ(error_of([&] { save_scene(invalid, path); }),
            "/materials: empty (a scene needs at least one material)");
  EXPECT_EQ(file_bytes(path), before);
  EXPECT_EQ(file_names(directory), std::vector<std::string>{"scene.hapticut.json"});

  Scene changed = scene;
  changed.stiffness_N_per_mm = 0.2;
  save_scene(changed, path);
  EXPECT_EQ(load_scene(path).stiffness_N_per_mm, 0.2);
  EXPECT_EQ(file_names(directory), std::vector<std::string>{"scene.hapticut.json"});
  fs::remove_all(directory);
}

TEST(SceneIo, FileErrorsNameTheFile) {
  const fs::path directory = scratch_directory("file_errors");
  const std::string missing = (directory / "absent" / "scene.hapticut.json").string();
  try {
    load_scene(missing);
    FAIL() << "no error";
  } catch (const SceneError& error) {
    EXPECT_EQ(error.field(), "(file)");
    EXPECT_NE(std::string(error.what()).find(missing), std::string::npos);
  }
  EXPECT_EQ(error_of([&] { save_scene(load_scene(kExamplePath), missing); }).rfind("(file): ", 0),
            0u);
  fs::remove_all(directory);
}

// 200k tets through a MessagePack file: correctness here; the time is printed,
// not asserted (benchmarks print, tests do not time).
TEST(SceneIo, TwoHundredThousandTetsThroughMessagePack) {
  std::vector<double> planes(34);
  for (std::size_t i = 0; i < planes.size(); ++i) planes[i] = static_cast<double>(i);
  const MeshData mesh =
      grid_mesh(planes, planes, std::vector<double>(planes.begin(), planes.end() - 1));
  Scene scene = load_scene(kExamplePath);
  scene.vertices_mm = mesh.vertices_mm;
  scene.tets = mesh.tets;
  scene.tet_materials.assign(mesh.tets.size(), 1);
  ASSERT_GE(scene.tets.size(), 200000u);

  const fs::path directory = scratch_directory("large");
  const std::string path = (directory / "grid.hapticut.msgpack").string();
  save_scene(scene, path);
  const auto start = std::chrono::steady_clock::now();
  const SceneDocument loaded = load_scene_document(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("load %zu tets, %.1f MB MessagePack: %.3f s\n", loaded.scene.tets.size(),
              static_cast<double>(fs::file_size(path)) / 1e6, seconds);
  RecordProperty("load_seconds", std::to_string(seconds));
  EXPECT_EQ(loaded.scene.vertices_mm, scene.vertices_mm);
  EXPECT_EQ(loaded.scene.tet_materials, scene.tet_materials);
  EXPECT_EQ(loaded.scene.tets, scene.tets);
  EXPECT_EQ(loaded.reoriented_tets, 0);
  fs::remove_all(directory);
}

}  // namespace
}  // namespace hapticut
