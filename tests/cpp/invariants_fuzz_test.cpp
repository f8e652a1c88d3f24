// Invariant and fuzz tests: random meshes
// with slivers and large fans, random trajectories with jumps across many
// tets. Device points also land exactly on vertices, edges and faces, and
// segments q -> p run exactly through boundary vertices, edges and faces,
// along face planes (putting p on a feature alone never drives the segment
// through one). After every tick: q finite, the state
// agrees with q, q outside every rigid tet, an OUTSIDE q outside the mesh;
// stepping again with the same p changes nothing; rigid layers one tet thick
// are never crossed. At least 10^6 steps run here; HAPTICUT_FUZZ_STEPS raises
// it (tests/run_long_fuzz.sh).
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>

#include "hapticut/proxy.h"
#include "test_support.h"

namespace hapticut {
namespace {

using testing::make_space;

std::int64_t steps_per_scenario(std::int64_t minimum) {
  const char* env = std::getenv("HAPTICUT_FUZZ_STEPS");
  return env != nullptr ? std::max<std::int64_t>(minimum, std::atoll(env)) : minimum;
}

std::vector<Material> all_materials() {
  std::vector<Material> materials = testing::paper_materials();
  Material fluid{"fluid", MaterialModel::Viscous};
  fluid.viscosity_N_s_per_mm = 0.002;
  fluid.max_lag_mm = 3.0;
  Material skin{"skin", MaterialModel::Membrane};
  skin.break_force_N = 0.3;
  materials.push_back(fluid);
  materials.push_back(skin);
  return materials;
}

struct Box {
  Vec3 lo, hi;
};

Box bounds(const MeshData& mesh) {
  Box b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (const Vec3& v : mesh.vertices_mm) {
    b.lo = {std::min(b.lo.x, v.x), std::min(b.lo.y, v.y), std::min(b.lo.z, v.z)};
    b.hi = {std::max(b.hi.x, v.x), std::max(b.hi.y, v.y), std::max(b.hi.z, v.z)};
  }
  return b;
}

// Two device points whose segment runs exactly through a feature of the
// mesh boundary: a boundary vertex, a point of a boundary edge or of a
// boundary face, along a face plane through it, along an edge, or into or
// out of a tet there. The first point brings the proxy (OUTSIDE: q = p) to one
// end; the second drives q -> p through the feature.
struct FeaturePath {
  Vec3 first;
  Vec3 second;
};

template <class Rng>
FeaturePath path_through_boundary_feature(const TetMesh& mesh, Rng& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto& faces = mesh.boundary_faces();
  const FaceRef face = faces[rng() % faces.size()];
  const auto& tet = mesh.tet(face.tet);
  std::array<int, 3> corner{};
  for (int v = 0, n = 0; v < 4; ++v) {
    if (v != face.face) corner[n++] = v;
  }
  auto centre_of = [&](std::int32_t t) {
    Vec3 c;
    for (std::int32_t w : mesh.tet(t)) c += mesh.vertex(w) * 0.25;
    return c;
  };
  Vec3 at;
  Vec3 direction;
  const int feature = static_cast<int>(rng() % 3);
  const int kind = static_cast<int>(rng() % 3);
  if (feature == 0) {  // A boundary vertex, and any tet around it.
    const std::int32_t vertex = tet[corner[rng() % 3]];
    at = mesh.vertex(vertex);
    const auto fan = mesh.vertex_fan(vertex);
    const VertexFanEntry entry = fan[rng() % fan.size()];
    const auto& around = mesh.tet(entry.tet);
    const int other = (entry.local_vertex + 1 + static_cast<int>(rng() % 3)) % 4;
    if (kind == 0) {  // Along the plane of a face through the vertex.
      Vec3 c;
      for (int w = 0; w < 4; ++w) {
        if (w != other) c += mesh.vertex(around[w]) / 3.0;
      }
      direction = c - at;
    } else if (kind == 1) {  // Along an edge.
      direction = mesh.vertex(around[other]) - at;
    } else {  // Into the tet.
      direction = centre_of(entry.tet) - at;
    }
  } else if (feature == 1) {  // A point of a boundary edge, and any tet around it.
    const int side = corner[rng() % 3];
    const int local_edge = kEdgeOfFaces[face.face][side];
    const std::int32_t e = mesh.edge_of(face.tet, local_edge);
    const Vec3& a = mesh.vertex(mesh.edge_vertices(e)[0]);
    const Vec3& b = mesh.vertex(mesh.edge_vertices(e)[1]);
    at = a + (b - a) * unit(rng);
    const auto fan = mesh.edge_fan(e);
    const EdgeFanEntry entry = fan[rng() % fan.size()];
    if (kind == 0) {  // Along the plane of a face through the edge.
      const int opposite = entry.faces[rng() % 2];
      const auto& around = mesh.tet(entry.tet);
      // The face's corner off the edge: its local vertices are all but `opposite`.
      Vec3 off_edge;
      for (int w = 0; w < 4; ++w) {
        const Vec3& x = mesh.vertex(around[w]);
        if (w != opposite && !(x == a) && !(x == b)) off_edge = x;
      }
      direction = off_edge - at;
    } else if (kind == 1) {
      direction = b - a;
    } else {
      direction = centre_of(entry.tet) - at;
    }
  } else {  // A point of a boundary face.
    const double u = unit(rng);
    const double v = unit(rng) * (1.0 - u);
    const Vec3& a = mesh.vertex(tet[corner[0]]);
    const Vec3& b = mesh.vertex(tet[corner[1]]);
    const Vec3& c = mesh.vertex(tet[corner[2]]);
    at = a + (b - a) * u + (c - a) * v;
    direction = kind == 0 ? mesh.vertex(tet[corner[rng() % 3]]) - at : centre_of(face.tet) - at;
  }
  if (rng() % 2 == 0) direction = -direction;
  return {at - direction * (0.05 + unit(rng)), at + direction * (0.05 + unit(rng))};
}

bool same_place_and_force(const Proxy& a, const Proxy& b) {
  return a.place().state == b.place().state && a.place().tet == b.place().tet &&
         a.place().local == b.place().local && a.q() == b.q() && a.force_N() == b.force_N();
}

// Stepping again with the same p changes nothing (place, force). With a
// speed-dependent material the first repeat sees the speed drop to zero, so
// the second repeat is compared with the first.
std::string check_repeat_changes_nothing(const Proxy& proxy, const Vec3& p, bool uses_speed) {
  Proxy twin = proxy;
  if (uses_speed && twin.step(p, 0.001).capped) return "";
  const Proxy before = twin;
  if (twin.step(p, 0.001).capped) return "";
  if (same_place_and_force(before, twin)) return "";
  return std::string("stepping again with the same p moved the proxy from ") +
         proxy_state_name(before.place().state) + " to " + proxy_state_name(twin.place().state);
}

// A random walk of several proxies: small steps, sliding strokes, now and
// then a jump anywhere in (and a little beyond) the mesh's box, and paths
// exactly through boundary features.
std::int64_t run_walk(const Space& space, const MeshData& mesh, std::int64_t steps,
                      std::uint64_t seed, bool expect_vertex = true) {
  std::mt19937_64 rng(seed);
  const Box box = bounds(mesh);
  const Vec3 size = box.hi - box.lo;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto anywhere = [&] {
    return Vec3{box.lo.x - 0.1 * size.x + 1.2 * size.x * unit(rng),
                box.lo.y - 0.1 * size.y + 1.2 * size.y * unit(rng),
                box.lo.z - 0.1 * size.z + 1.2 * size.z * unit(rng)};
  };
  const double scale = norm(size);
  std::vector<Proxy> proxies(8, Proxy(space));
  std::vector<Vec3> points(proxies.size());
  std::vector<Vec3> pending(proxies.size());
  std::vector<bool> has_pending(proxies.size(), false);
  for (std::size_t i = 0; i < proxies.size(); ++i) {
    points[i] = anywhere();
    proxies[i].reset(points[i]);
  }
  std::int64_t capped = 0;
  for (std::int64_t s = 0; s < steps; ++s) {
    const std::size_t i = static_cast<std::size_t>(s) % proxies.size();
    const double kind = unit(rng);
    if (has_pending[i]) {
      points[i] = pending[i];  // The second half of a path through a boundary feature.
      has_pending[i] = false;
    } else if (kind < 0.05) {
      const FeaturePath path = path_through_boundary_feature(space.mesh(), rng);
      points[i] = path.first;
      pending[i] = path.second;
      has_pending[i] = true;
    } else if (kind < 0.07) {
      points[i] = anywhere();  // A jump across many tets in one tick.
    } else if (kind < 0.09) {
      // Exactly on a vertex, an edge or a face: where strict tests go wrong.
      const auto& tet = mesh.tets[rng() % mesh.tets.size()];
      const Vec3& a = mesh.vertices_mm[tet[0]];
      const Vec3& b = mesh.vertices_mm[tet[1]];
      const Vec3& c = mesh.vertices_mm[tet[2]];
      const int which = static_cast<int>(rng() % 3);
      points[i] = which == 0 ? a : (which == 1 ? (a + b) * 0.5 : (a + b + c) / 3.0);
    } else {
      const double step = kind < 0.5 ? 1e-3 * scale : 2e-2 * scale;
      points[i] += Vec3{gauss(rng), gauss(rng), gauss(rng)} * step;
    }
    const TickResult r = proxies[i].step(points[i], 0.001);
    capped += r.capped ? 1 : 0;
    std::string problem = proxies[i].check_invariants();
    if (problem.empty() && !r.capped) {
      problem = check_repeat_changes_nothing(proxies[i], points[i], space.uses_speed());
    }
    if (!problem.empty()) {
      ADD_FAILURE() << "step " << s << ", proxy " << i << ", state "
                    << proxy_state_name(proxies[i].place().state) << ": " << problem;
      return capped;
    }
  }
  // The walk must have reached every state, or it proved little.
  std::array<std::uint64_t, kProxyStateCount> entered{};
  for (const Proxy& proxy : proxies) {
    for (int from = 0; from < kProxyStateCount; ++from) {
      for (int to = 0; to < kProxyStateCount; ++to) {
        entered[to] +=
            proxy.counters().transitions[from][to][0] + proxy.counters().transitions[from][to][1];
      }
    }
  }
  for (int state = 0; state < kProxyStateCount; ++state) {
    if (!expect_vertex && ProxyState(state) == ProxyState::Vertex) continue;
    EXPECT_GT(entered[state], 0u) << "never entered " << proxy_state_name(ProxyState(state));
  }
  return capped;
}

std::vector<std::int32_t> random_materials(std::size_t tets, std::uint64_t seed, int count) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> pick(0, count - 1);
  std::vector<std::int32_t> m(tets);
  for (auto& x : m) x = pick(rng);
  return m;
}

TEST(Invariants, JitteredGridWithSliversAndAllMaterials) {
  const MeshData mesh =
      grid_mesh({0, 7, 15, 16, 30, 41}, {0, 9, 12, 25, 33}, {0, 10, 19, 20.5, 32}, 0.45, 11);
  const auto space_owner =
      make_space(mesh, random_materials(mesh.tets.size(), 3, 5), all_materials());
  const Space& space = *space_owner;
  EXPECT_LT(space.mesh().stats().min_dihedral_deg, 5.0) << "the mesh should contain slivers";
  EXPECT_GE(space.mesh().stats().max_tets_per_vertex, 20);
  run_walk(space, mesh, steps_per_scenario(400000), 101);
}

TEST(Invariants, EdgeSharedBySixteenTetsAndFlatSlivers) {
  for (double half_height : {10.0, 0.05}) {
    const MeshData mesh = edge_fan_mesh(16, 10.0, half_height);
    const auto space_owner =
        make_space(mesh, random_materials(mesh.tets.size(), 5, 5), all_materials());
    const Space& space = *space_owner;
    EXPECT_EQ(space.mesh().stats().max_tets_per_edge, 16);
    run_walk(space, mesh, steps_per_scenario(150000), 202, /*expect_vertex=*/false);
  }
}

TEST(Invariants, IcosahedronCentreSharedByTwentyTets) {
  const MeshData mesh = icosahedron_mesh(10.0);
  const auto space_owner =
      make_space(mesh, random_materials(mesh.tets.size(), 9, 5), all_materials());
  const Space& space = *space_owner;
  EXPECT_EQ(space.mesh().stats().max_tets_per_vertex, 20);
  run_walk(space, mesh, steps_per_scenario(150000), 303);
}

TEST(Invariants, MostlyRigidGridKeepsProxiesOut) {
  const MeshData mesh = grid_mesh({0, 5, 10, 15, 20}, {0, 5, 10, 15, 20}, {0, 5, 10, 15}, 0.3, 4);
  std::mt19937_64 rng(17);
  std::vector<std::int32_t> m(mesh.tets.size());
  for (auto& x : m) x = (rng() % 10 < 6) ? 2 : int(rng() % 2);
  const auto space_owner = make_space(mesh, m);
  const Space& space = *space_owner;
  run_walk(space, mesh, steps_per_scenario(200000), 404);
}

// A rigid layer of a single cell, w thick, between two free layers; the
// device point jumps straight across it in one tick, or wanders below it.
TEST(Invariants, ThinRigidLayerIsNeverCrossed) {
  for (double w : {1.0, 1e-3, 1e-7}) {
    const MeshData mesh = grid_mesh({0, 10, 20, 30}, {0, 10, 20, 30}, {0, 10, 10 + w, 20}, 0.0);
    std::vector<std::int32_t> m(mesh.tets.size(), 0);
    for (std::size_t t = 0; t < mesh.tets.size(); ++t) {
      double z = 0;
      for (std::int32_t v : mesh.tets[t]) z += mesh.vertices_mm[v].z * 0.25;
      if (z > 10 && z < 10 + w) m[t] = 2;
    }
    const auto space_owner = make_space(mesh, m);
    const Space& space = *space_owner;
    std::mt19937_64 rng(99);
    std::uniform_real_distribution<double> xy(0.5, 29.5);
    std::uniform_real_distribution<double> below(-5.0, 9.9);
    std::uniform_real_distribution<double> above(10.5 + w, 19.5);
    for (int trial = 0; trial < 2000; ++trial) {
      Proxy proxy(space);
      proxy.reset({xy(rng), xy(rng), above(rng)});
      for (int k = 0; k < 10; ++k) {
        proxy.step({xy(rng), xy(rng), below(rng)}, 0.001);
        ASSERT_GE(proxy.q().z, 10 + w - 1e3 * space.tolerance()) << "w = " << w;
        ASSERT_EQ(proxy.check_invariants(), "") << "w = " << w;
      }
    }
  }
}

}  // namespace
}  // namespace hapticut
