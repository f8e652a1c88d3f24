// Cut memory (docs/decisions.md, "Cut memory"): tissue once cut
// stays cut. A blade drawn back through its own slit feels the material's cut
// variant (cut_to), a stroke beside it the uncut material; skin opened once
// is not broken again; the cut set follows from the stroke alone; the scene
// file keeps cut_to in both encodings and refuses a bad one, naming the material.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "hapticut/blade.h"
#include "hapticut/cut_state.h"
#include "hapticut/scene_io.h"
#include "test_support.h"

#ifndef HAPTICUT_TEST_DATA_DIR
#define HAPTICUT_TEST_DATA_DIR "tests/data"
#endif

namespace hapticut {
namespace {

using testing::axis;
using testing::make_space;

constexpr double kDt = 0.001;
constexpr double kStiffness = 0.1;  // N/mm, EngineSettings' default.

Material drag(const std::string& name, double d_mm, const std::string& cut_to = "") {
  Material m{name, MaterialModel::Drag};
  m.drag_distance_mm = d_mm;
  m.cut_to = cut_to;
  return m;
}

Material skin(double break_force_N, const std::string& cut_to) {
  Material m{"skin", MaterialModel::Membrane};
  m.break_force_N = break_force_N;
  m.cut_to = cut_to;
  return m;
}

// A block on a 2.5 mm grid, x in [-20, 20], y in [-10, 10], z in [-15, 10]:
// each tet labelled by label(its centroid). The strokes run off the grid's planes.
std::shared_ptr<const Space> block(const std::vector<Material>& materials,
                                   const std::function<std::int32_t(const Vec3&)>& label) {
  const MeshData mesh = grid_mesh(axis(-20, 20, 2.5), axis(-10, 10, 2.5), axis(-15, 10, 2.5));
  std::vector<std::int32_t> labels(mesh.tets.size());
  for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
    Vec3 c;
    for (std::int32_t v : mesh.tets[t]) c += mesh.vertices_mm[v] * 0.25;
    labels[t] = label(c);
  }
  return make_space(mesh, labels, materials);
}

// A slab of flesh (drag 4 mm, cut_to flesh_cut: drag 0.4 mm) for |x| < 10,
// z < 0, air round it.
std::shared_ptr<const Space> flesh_block() {
  return block(
      {{"air", MaterialModel::Free}, drag("flesh", 4.0, "flesh_cut"), drag("flesh_cut", 0.4)},
      [](const Vec3& c) { return std::abs(c.x) < 10.0 && c.z < 0.0 ? 1 : 0; });
}

// Air above z = 0, skin (membrane breaking at 0.5 N, cut_to air) for 2.5 mm,
// flesh (drag 1 mm) below.
std::shared_ptr<const Space> skin_block() {
  return block({{"air", MaterialModel::Free}, skin(0.5, "air"), drag("flesh", 1.0)},
               [](const Vec3& c) { return c.z > 0.0    ? 0
                                          : c.z > -2.5 ? 1
                                                       : 2; });
}

// One point (independent), or a rigid edge of three points 2 mm long, upright.
BladeSpec knife(BladeCoupling coupling) {
  BladeSpec spec{"knife", {0, 0, 0}, {0, 0, 0}, 1};
  if (coupling == BladeCoupling::Rigid) spec = {"knife", {0, 0, -1}, {0, 0, 1}, 3};
  spec.coupling = coupling;
  return spec;
}

// Steps the blade along straight moves of the tool origin, `ticks` each.
// Returns the largest |force| over the ticks where `measured(p)` holds.
double stroke(Blade& blade, const std::vector<Vec3>& corners, int ticks,
              const std::function<bool(const Vec3&)>& measured) {
  double most = 0.0;
  for (std::size_t c = 0; c + 1 < corners.size(); ++c) {
    for (int k = 1; k <= ticks; ++k) {
      const Vec3 p = corners[c] + (corners[c + 1] - corners[c]) * (double(k) / ticks);
      const BladeTick tick = blade.step({p, {}}, kDt);
      if (measured(p)) most = std::max(most, norm(tick.force_N));
    }
  }
  return most;
}

// Through the slab along x at y, 5.6 mm deep, from the air on one side to
// the air on the other: the largest force over x in [-2, 8], where the point
// trails on the line (its q moves along it, toward p). The lines keep off the
// planes of the grid's Kuhn tets that run along x.
double slit(Blade& blade, double y) {
  const std::vector<Vec3> corners{{-18, y, -5.6}, {18, y, -5.6}};
  blade.reset({corners[0], {}});
  return stroke(blade, corners, 3600, [](const Vec3& p) { return p.x >= -2.0 && p.x <= 8.0; });
}

// Down through the skin at (x, y) to 8 mm deep and out again: the largest
// force on the way down.
double press(Blade& blade, double x, double y) {
  const std::vector<Vec3> corners{{x, y, 5}, {x, y, -8}, {x, y, 5}};
  blade.reset({corners[0], {}});
  double most = 0.0;
  for (int k = 1; k <= 2600; ++k) {
    const Vec3 p = corners[0] + (corners[1] - corners[0]) * (k / 2600.0);
    most = std::max(most, norm(blade.step({p, {}}, kDt).force_N));
  }
  stroke(blade, {corners[1], corners[2]}, 2600, [](const Vec3&) { return false; });
  return most;
}

class CutMemory : public ::testing::TestWithParam<BladeCoupling> {};

TEST_P(CutMemory, ReentryInTheSlitFeelsTheCutMaterial) {
  const auto space = flesh_block();
  Blade blade(space, knife(GetParam()));
  const double points = blade.point_count();
  const double first = slit(blade, 0.6);
  EXPECT_NEAR(first, kStiffness * 4.0 * points, 0.02 * points) << first;  // Uncut: drag 4 mm.
  EXPECT_GT(blade.cuts().cut_count(), 0);
  const double second = slit(blade, 0.6);
  // Cut: drag 0.4 mm, at most its force.
  EXPECT_LE(second, kStiffness * 0.4 * points + 1e-9);
  EXPECT_GT(second, 0.5 * kStiffness * 0.4 * points);
}

TEST_P(CutMemory, AStrokeBesideTheSlitFeelsTheUncutMaterial) {
  const auto space = flesh_block();
  Blade blade(space, knife(GetParam()));
  const double first = slit(blade, 0.6);
  const double beside = slit(blade, 5.6);
  EXPECT_NEAR(beside, first, 0.01 * first);
}

TEST_P(CutMemory, SkinOpenedOnceIsNotBrokenAgain) {
  const auto space = skin_block();
  Blade blade(space, knife(GetParam()));
  const double points = blade.point_count();
  // The blade's lowest point breaks the skin: it pushes 0.5 N before it gives.
  const double first = press(blade, 0.9, 0.35);
  EXPECT_GT(first, 0.45);
  bool skin_cut = false;
  for (std::int32_t t : blade.cuts().cut_tets())
    skin_cut = skin_cut || space->mesh().material(t) == 1;
  EXPECT_TRUE(skin_cut);
  // Again through the opening: the skin acts as air, only the flesh drags (1 mm).
  const double again = press(blade, 0.9, 0.35);
  EXPECT_LE(again, kStiffness * 1.0 * points + 1e-9);
  // Beside it the skin is whole.
  EXPECT_GT(press(blade, 5.9, 0.35), 0.45);
}

TEST_P(CutMemory, TheSameStrokeFromResetGivesTheSameCutSet) {
  const auto space = flesh_block();
  Blade blade(space, knife(GetParam()));
  slit(blade, 0.6);
  const std::vector<std::uint8_t> once(blade.cuts().bytes().begin(), blade.cuts().bytes().end());
  const std::int64_t count = blade.cuts().cut_count();
  EXPECT_GT(count, 10);
  blade.reset_cuts();
  EXPECT_EQ(blade.cuts().cut_count(), 0);
  EXPECT_EQ(blade.cuts().cut_tets(), std::vector<std::int32_t>{});
  slit(blade, 0.6);
  EXPECT_EQ(std::vector<std::uint8_t>(blade.cuts().bytes().begin(), blade.cuts().bytes().end()),
            once);
  EXPECT_EQ(blade.cuts().cut_count(), count);
  // A fresh blade on a fresh Space: the same bytes too.
  Blade fresh(flesh_block(), knife(GetParam()));
  slit(fresh, 0.6);
  EXPECT_EQ(std::vector<std::uint8_t>(fresh.cuts().bytes().begin(), fresh.cuts().bytes().end()),
            once);
  // Only flesh is cut, never air.
  for (std::int32_t t : blade.cuts().cut_tets()) EXPECT_EQ(space->mesh().material(t), 1);
}

TEST_P(CutMemory, TheCutOrderIsTheSetInTheOrderOfCuttingAndSetCutsRestoresIt) {
  const auto space = flesh_block();
  Blade blade(space, knife(GetParam()));
  const std::uint32_t fresh_generation = blade.cuts().generation();
  slit(blade, 0.6);
  const std::vector<std::int32_t> order(blade.cuts().cut_order().begin(),
                                        blade.cuts().cut_order().end());
  ASSERT_GT(order.size(), 10U);
  std::vector<std::int32_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted, blade.cuts().cut_tets());              // Each cut tet once.
  EXPECT_EQ(blade.cuts().generation(), fresh_generation);  // Cutting appends.

  // Another blade's state set from the order: the same bytes, the same order.
  Blade other(space, knife(GetParam()));
  other.set_cuts(order);
  EXPECT_NE(other.cuts().generation(), fresh_generation);
  EXPECT_TRUE(std::equal(other.cuts().bytes().begin(), other.cuts().bytes().end(),
                         blade.cuts().bytes().begin(), blade.cuts().bytes().end()));
  EXPECT_TRUE(std::equal(other.cuts().cut_order().begin(), other.cuts().cut_order().end(),
                         order.begin(), order.end()));

  // Refused, naming the entry, and the cuts stay as they were.
  const std::uint32_t before = other.cuts().generation();
  const std::int32_t air_tet = [&] {
    for (std::int32_t t = 0; t < space->mesh().tet_count(); ++t) {
      if (space->mesh().material(t) == 0) return t;
    }
    return -1;
  }();
  const std::vector<std::pair<std::vector<std::int32_t>, std::string>> refused{
      {{order[0], -3}, "cut tets/1: tet -3 is not one of the scene's"},
      {{order[0], order[1], order[0]},
       "cut tets/2: tet " + std::to_string(order[0]) + " is given twice"},
      {{air_tet},
       "cut tets/0: tet " + std::to_string(air_tet) + " is of a material that is never cut (free)"},
  };
  for (const auto& [tets, message] : refused) {
    try {
      other.set_cuts(tets);
      ADD_FAILURE() << "taken: " << message;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
    EXPECT_EQ(other.cuts().generation(), before);
    EXPECT_EQ(other.cuts().cut_count(), static_cast<std::int64_t>(order.size()));
  }
  other.reset_cuts();
  EXPECT_NE(other.cuts().generation(), before);
  EXPECT_TRUE(other.cuts().cut_order().empty());
}

// The blade `hapticut bench blade` weighs the memory's cost against: with the
// memory off it cuts nothing and feels the uncut flesh again and again; on
// again, it remembers from there.
TEST_P(CutMemory, ABladeWithoutMemoryCutsNothingAndFeelsTheUncutMaterial) {
  const auto space = flesh_block();
  Blade blade(space, knife(GetParam()));
  blade.set_cut_memory(false);
  EXPECT_FALSE(blade.cut_memory());
  const double first = slit(blade, 0.6);
  EXPECT_EQ(blade.cuts().cut_count(), 0);
  EXPECT_EQ(slit(blade, 0.6), first);
  blade.set_cut_memory(true);
  EXPECT_TRUE(blade.cut_memory());
  EXPECT_EQ(slit(blade, 0.6), first);
  EXPECT_GT(blade.cuts().cut_count(), 0);
  EXPECT_LE(slit(blade, 0.6), kStiffness * 0.4 * blade.point_count() + 1e-9);
}

// Two points 6 mm apart across the stroke, on a 2.5 mm grid: the tets between
// their paths, which neither point enters, are cut by the edge between them;
// a point drawn there afterwards feels the cut flesh.
TEST_P(CutMemory, TheEdgeCutsTheTetsBetweenItsPoints) {
  const auto space = flesh_block();
  BladeSpec wide{"knife", {0, -3, 0}, {0, 3, 0}, 2};
  wide.coupling = GetParam();
  auto cuts = std::make_shared<CutState>(space);
  Blade blade(space, wide, nullptr, cuts);
  const std::vector<Vec3> corners{{-18, 0.1, -5.6}, {18, 0.1, -5.6}};
  blade.reset({corners[0], {}});
  stroke(blade, corners, 3600, [](const Vec3&) { return false; });
  int between = 0;
  for (double x = -6.0; x <= 6.0; x += 1.0) {
    const std::int32_t t = space->mesh().locate({x, 0.1, -5.6});
    ASSERT_NE(t, kNoTet);
    between += blade.cuts().cut(t);
  }
  EXPECT_EQ(between, 13);
  Blade probe(space, knife(BladeCoupling::Independent), nullptr, cuts);
  EXPECT_LE(slit(probe, 0.1), kStiffness * 0.4 + 1e-9);
}

INSTANTIATE_TEST_SUITE_P(BothCouplings, CutMemory,
                         ::testing::Values(BladeCoupling::Independent, BladeCoupling::Rigid),
                         [](const ::testing::TestParamInfo<BladeCoupling>& info) {
                           return std::string(blade_coupling_name(info.param));
                         });

TEST(CutMemoryBlades, WithoutCutToACutTetStaysAsItIs) {
  const auto space = block({{"air", MaterialModel::Free}, drag("flesh", 4.0)},
                           [](const Vec3& c) { return std::abs(c.x) < 10.0 && c.z < 0.0 ? 1 : 0; });
  Blade blade(space, knife(BladeCoupling::Independent));
  const double first = slit(blade, 0.6);
  EXPECT_GT(blade.cuts().cut_count(), 0);  // Cut, as the bake sees it ...
  EXPECT_EQ(slit(blade, 0.6), first);      // ... and felt as before.
}

TEST(CutMemoryBlades, BladesOfOneSceneShareTheirCuts) {
  const auto space = flesh_block();
  auto cuts = std::make_shared<CutState>(space);
  Blade first(space, knife(BladeCoupling::Independent), nullptr, cuts);
  Blade second(space, knife(BladeCoupling::Independent), nullptr, cuts);
  slit(first, 0.6);
  EXPECT_LE(slit(second, 0.6), kStiffness * 0.4 + 1e-9);
  EXPECT_THROW(Blade(flesh_block(), knife(BladeCoupling::Independent), nullptr, cuts),
               std::invalid_argument);
}

TEST(CutMemoryBlades, TheMaterialATetActsAsGoesThroughTheCutByte) {
  const auto space = flesh_block();
  const TetMesh& mesh = space->mesh();
  const auto centre = [&mesh](std::int32_t t) {
    Vec3 c;
    for (std::int32_t v : mesh.tet(t)) c += mesh.vertex(v) * 0.25;
    return c;
  };
  // A flesh tet with flesh behind its face 0.
  std::int32_t flesh = 0;
  while (mesh.material(flesh) != 1 || mesh.neighbour(flesh, 0) == kNoTet ||
         mesh.material(mesh.neighbour(flesh, 0)) != 1) {
    ++flesh;
  }
  const std::int32_t next = mesh.neighbour(flesh, 0);
  CutState cuts(space);
  EXPECT_EQ(space->material_of_tet(flesh, &cuts).name, "flesh");
  // A point still in a tet has not cut it yet; one that has left it has.
  EXPECT_EQ(cuts.cut_along(flesh, centre(flesh), centre(flesh)), 0);
  EXPECT_EQ(cuts.cut_along(flesh, centre(flesh), centre(next)), 1);
  EXPECT_EQ(cuts.cut_along(flesh, centre(flesh), centre(next)), 0);  // Once.
  EXPECT_EQ(cuts.cut(flesh), 1);
  EXPECT_EQ(cuts.cut(next), 0);
  EXPECT_EQ(space->material_of_tet(flesh, &cuts).name, "flesh_cut");
  EXPECT_EQ(space->tet_model(flesh, &cuts), MaterialModel::Drag);
  EXPECT_EQ(space->material_of_tet(flesh, nullptr).name, "flesh");
  EXPECT_EQ(cuts.cut_tets(), std::vector<std::int32_t>{flesh});
  // Along a face: inside neither tet, cuts neither.
  const Vec3 a = mesh.vertex(mesh.tet(flesh)[1]);
  const Vec3 b = mesh.vertex(mesh.tet(flesh)[2]);
  CutState along_face(space);
  EXPECT_EQ(along_face.cut_along(flesh, a, b), 0);
}

// --- The scene file ---------------------------------------------------------------------------

const std::string kExamplePath = std::string(HAPTICUT_TEST_DATA_DIR) + "/two_tets.hapticut.json";

// The example with a third material, flesh_cut, and flesh cut to it.
Scene scene_with_cut_to() {
  Scene scene = load_scene(kExamplePath);
  scene.materials.push_back(drag("flesh_cut", 0.1));
  scene.materials[1].cut_to = "flesh_cut";
  return scene;
}

std::string write_error(Scene scene, SceneEncoding encoding) {
  try {
    serialize_scene(scene, encoding);
  } catch (const SceneError& error) {
    return error.what();
  }
  return "no error";
}

TEST(CutMemoryScene, CutToRoundTripsInBothEncodings) {
  const Scene scene = scene_with_cut_to();
  for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
    const Scene again = parse_scene(serialize_scene(scene, encoding), encoding);
    ASSERT_EQ(again.materials.size(), 3u);
    EXPECT_EQ(again.materials[0].cut_to, "");
    EXPECT_EQ(again.materials[1].cut_to, "flesh_cut");
    EXPECT_EQ(again.materials[2].cut_to, "");
    EXPECT_EQ(Space::from_scene(again)->cut_variants(), (std::vector<std::int32_t>{0, 2, 2}));
  }
  const auto json = serialize_scene(scene, SceneEncoding::Json);
  const std::string text(json.begin(), json.end());
  EXPECT_NE(text.find(R"("cut_to": "flesh_cut")"), std::string::npos);
  // Without one, none is written: files of scenes without cut memory do not change.
  const auto plain = serialize_scene(load_scene(kExamplePath), SceneEncoding::Json);
  EXPECT_EQ(std::string(plain.begin(), plain.end()).find("cut_to"), std::string::npos);
}

TEST(CutMemoryScene, BadCutToNamesTheMaterialInBothEncodings) {
  struct Case {
    std::function<void(Scene&)> edit;
    std::string error;
  };
  const std::vector<Case> cases{
      {[](Scene& s) { s.materials[1].cut_to = "gristle"; },
       "/materials/1/cut_to: material 'flesh': cut_to names no material of the scene "
       "('gristle')"},
      {[](Scene& s) { s.materials[0].cut_to = "flesh"; },
       "/materials/0/cut_to: material 'air' is free: only drag, viscous and membrane are cut, so "
       "only they take a cut_to"},
      {[](Scene& s) {
         s.materials.push_back({"bone", MaterialModel::Rigid});
         s.materials.back().cut_to = "air";
       },
       "/materials/3/cut_to: material 'bone' is rigid: only drag, viscous and membrane are cut, "
       "so only they take a cut_to"},
      {[](Scene& s) {
         s.materials.push_back({"bone", MaterialModel::Rigid});
         s.materials[1].cut_to = "bone";
       },
       "/materials/1/cut_to: material 'flesh': cut_to 'bone' is rigid (a cut never makes a tet "
       "rigid)"},
      {[](Scene& s) { s.materials[2].cut_to = "flesh"; },
       "/materials/1/cut_to: material 'flesh': cut_to makes a cycle ('flesh' -> 'flesh_cut' -> "
       "'flesh')"},
      {[](Scene& s) { s.materials[1].cut_to = "flesh"; },
       "/materials/1/cut_to: material 'flesh': cut_to makes a cycle ('flesh' -> 'flesh')"},
  };
  for (const Case& c : cases) {
    Scene scene = scene_with_cut_to();
    c.edit(scene);
    for (SceneEncoding encoding : {SceneEncoding::Json, SceneEncoding::MessagePack}) {
      EXPECT_EQ(write_error(scene, encoding), c.error);
    }
    // The engine refuses the same materials, with the same reason.
    try {
      Space::create(TetMesh(scene.vertices_mm, scene.tets, scene.tet_materials), scene.materials);
      ADD_FAILURE() << "no error for " << c.error;
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(c.error.find(error.what()), std::string::npos) << error.what();
    }
  }
}

TEST(CutMemoryScene, TheReaderRefusesACutToThatIsNoName) {
  for (const char* value : {R"("")", "3", "null"}) {
    std::string text = R"({"format": "hapticut.scene", "version": 1,
      "units": {"length": "mm", "force": "N", "time": "s"},
      "materials": [{"name": "air", "model": "free"},
                    {"name": "flesh", "model": "drag", "drag_distance_mm": 1.0, "cut_to": )" +
                       std::string(value) + R"(}],
      "mesh": {"vertices": [[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]],
               "tets": [[0, 1, 2, 3]], "tet_materials": [1]}})";
    const std::vector<std::uint8_t> bytes(text.begin(), text.end());
    try {
      parse_scene(bytes, SceneEncoding::Json);
      ADD_FAILURE() << "no error for cut_to " << value;
    } catch (const SceneError& error) {
      EXPECT_EQ(error.field(), "/materials/1/cut_to") << value;
    }
  }
}

}  // namespace
}  // namespace hapticut
