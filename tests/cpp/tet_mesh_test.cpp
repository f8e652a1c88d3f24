#include "hapticut/tet_mesh.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "hapticut/reference_meshes.h"

namespace hapticut {
namespace {

TetMesh build(const MeshData& d) {
  return TetMesh(d.vertices_mm, d.tets, std::vector<std::int32_t>(d.tets.size(), 0));
}

std::int64_t error_index(const MeshData& d) {
  try {
    build(d);
  } catch (const MeshError& e) {
    return e.index();
  }
  return -100;
}

TEST(TetMesh, RejectsVertexIndexOutOfRange) {
  MeshData d = two_tets_mesh();
  d.tets[1][3] = 99;
  EXPECT_EQ(error_index(d), 1);
}

TEST(TetMesh, RejectsNanCoordinateNamingTheVertex) {
  MeshData d = two_tets_mesh();
  d.vertices_mm[3].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_index(d), 3);
  d.vertices_mm[3].y = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_index(d), 3);
}

TEST(TetMesh, RejectsZeroVolumeTet) {
  MeshData d = two_tets_mesh();
  d.vertices_mm[4] = {5, 5, 0};  // Tet 1's apex in the plane of its base.
  EXPECT_EQ(error_index(d), 1);
}

TEST(TetMesh, RejectsFaceSharedByThreeTets) {
  MeshData d = two_tets_mesh();
  d.vertices_mm.push_back({0.3, 0.2, 5});
  d.tets.push_back({0, 1, 2, 5});
  EXPECT_GE(error_index(d), 0);
}

TEST(TetMesh, RejectsEmptyMeshAndMismatchedMaterials) {
  EXPECT_THROW(TetMesh({}, {}, {}), MeshError);
  const MeshData d = two_tets_mesh();
  EXPECT_THROW(TetMesh(d.vertices_mm, d.tets, {0}), MeshError);
}

TEST(TetMesh, ReorientsInvertedTets) {
  MeshData d = two_tets_mesh();
  std::swap(d.tets[0][0], d.tets[0][1]);
  const TetMesh mesh = build(d);
  EXPECT_EQ(mesh.stats().reoriented_tets, 1);
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) EXPECT_GT(mesh.signed_volume(t), 0.0);
}

TEST(TetMesh, FacePlanesPointOutwardAndNeighboursAgree) {
  const TetMesh mesh = build(grid_mesh({0, 1, 2.5, 3}, {0, 2, 3}, {0, 1, 2}, 0.3, 7));
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    Vec3 centroid;
    for (std::int32_t v : mesh.tet(t)) centroid += mesh.vertex(v) * 0.25;
    for (int f = 0; f < 4; ++f) {
      EXPECT_LT(mesh.face_plane(t, f).signed_distance(centroid), 0.0);
      EXPECT_NEAR(mesh.face_plane(t, f).signed_distance(mesh.vertex(mesh.tet(t)[(f + 1) % 4])), 0.0,
                  1e-12);
      const std::int32_t u = mesh.neighbour(t, f);
      if (u == kNoTet) continue;
      const int g = mesh.neighbour_face(t, f);
      EXPECT_EQ(mesh.neighbour(u, g), t);
      // Exactly opposite planes: no gap between neighbours.
      EXPECT_EQ(mesh.face_plane(u, g).normal, -mesh.face_plane(t, f).normal);
      EXPECT_EQ(mesh.face_plane(u, g).offset, -mesh.face_plane(t, f).offset);
    }
  }
}

TEST(TetMesh, FansMatchThePapersSetups) {
  const TetMesh fan = build(edge_fan_mesh(12));
  const std::int32_t axis = fan.edge_of(0, kEdgeOfVertices[0][1]);
  EXPECT_EQ(fan.edge_fan(axis).size(), 12u);
  EXPECT_FALSE(fan.is_boundary_edge(axis));
  EXPECT_EQ(fan.stats().max_tets_per_edge, 12);

  const TetMesh ico = build(icosahedron_mesh());
  EXPECT_EQ(ico.vertex_fan(0).size(), 20u);
  EXPECT_FALSE(ico.is_boundary_vertex(0));
  EXPECT_EQ(ico.boundary_faces().size(), 20u);

  const TetMesh cube = build(cube_mesh());
  EXPECT_EQ(cube.tet_count(), 6);
  EXPECT_EQ(cube.boundary_faces().size(), 12u);
}

TEST(TetMesh, BoundarySidePlanesAreTheOtherFacesOfEachBoundaryFacesTet) {
  for (const MeshData& data : {cube_mesh(), icosahedron_mesh(), edge_fan_mesh(12)}) {
    const TetMesh mesh = build(data);
    for (std::size_t k = 0; k < mesh.boundary_faces().size(); ++k) {
      const FaceRef& face = mesh.boundary_faces()[k];
      for (int j = 0; j < 3; ++j) {
        const Plane& expected = mesh.face_plane(face.tet, kOtherFaces[face.face][j]);
        const Plane& side = mesh.boundary_side_planes(k)[j];
        EXPECT_EQ(side.normal, expected.normal) << "boundary face " << k << ", side " << j;
        EXPECT_EQ(side.offset, expected.offset) << "boundary face " << k << ", side " << j;
      }
    }
  }
}

TEST(TetMesh, EachTetsPlanesStartOnACacheLine) {
  // Two lines a tet, never three: a walk into a new tet misses at most twice on its planes.
  const TetMesh mesh = build(grid_mesh({0, 1, 2, 3}, {0, 1, 2}, {0, 1, 2}, 0.2, 7));
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    const auto address = reinterpret_cast<std::uintptr_t>(&mesh.face_plane(t, 0));
    EXPECT_EQ(address % 64, 0U) << "tet " << t;
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(&mesh.face_plane(t, 3)) - address,
              3 * sizeof(Plane));
  }
}

// The fan an EDGE step reads from its tet (edge_fan_of) is the edge's own fan,
// entry for entry, and holds that tet at that local edge.
TEST(TetMesh, TheFanFoundFromATetIsTheEdgesFan) {
  const TetMesh mesh = build(grid_mesh({0, 1, 2, 3}, {0, 1, 2}, {0, 1, 2}, 0.2, 5));
  for (std::int32_t t = 0; t < mesh.tet_count(); ++t) {
    for (int local_edge = 0; local_edge < 6; ++local_edge) {
      const auto by_tet = mesh.edge_fan_of(t, local_edge);
      const auto by_edge = mesh.edge_fan(mesh.edge_of(t, local_edge));
      ASSERT_EQ(by_tet.data(), by_edge.data()) << "tet " << t << " edge " << local_edge;
      ASSERT_EQ(by_tet.size(), by_edge.size()) << "tet " << t << " edge " << local_edge;
      const bool holds_it = std::any_of(by_tet.begin(), by_tet.end(), [&](const EdgeFanEntry& f) {
        return f.tet == t && f.local_edge == local_edge;
      });
      EXPECT_TRUE(holds_it) << "tet " << t << " edge " << local_edge;
    }
  }
}

TEST(TetMesh, EdgeDirectionsAndFanFacesContainTheEdge) {
  const TetMesh mesh = build(grid_mesh({0, 1, 2}, {0, 1, 2}, {0, 1, 2}, 0.2, 3));
  for (std::int32_t e = 0; e < mesh.edge_count(); ++e) {
    const auto& ends = mesh.edge_vertices(e);
    const Vec3 d = mesh.vertex(ends[1]) - mesh.vertex(ends[0]);
    EXPECT_NEAR(norm(mesh.edge_direction(e) - d / norm(d)), 0.0, 1e-12);
    for (const EdgeFanEntry& entry : mesh.edge_fan(e)) {
      for (int side = 0; side < 2; ++side) {
        const Plane& plane = mesh.face_plane(entry.tet, entry.faces[side]);
        EXPECT_NEAR(plane.signed_distance(mesh.vertex(ends[0])), 0.0, 1e-12);
        EXPECT_NEAR(plane.signed_distance(mesh.vertex(ends[1])), 0.0, 1e-12);
      }
    }
  }
}

TEST(TetMesh, LocatesPointsAndReportsOutside) {
  const TetMesh mesh = build(grid_mesh({0, 1, 2, 3}, {0, 1, 2, 3}, {0, 1, 2, 3}, 0.25, 5));
  for (double x = 0.05; x < 3; x += 0.37) {
    for (double y = 0.05; y < 3; y += 0.41) {
      const Vec3 p{x, y, 1.3};
      const std::int32_t t = mesh.locate(p);
      ASSERT_NE(t, kNoTet);
      EXPECT_LE(mesh.outside_distance(t, p), mesh.tolerance());
    }
  }
  EXPECT_EQ(mesh.locate({5, 5, 5}), kNoTet);
  EXPECT_EQ(mesh.locate({-0.1, 1, 1}), kNoTet);
}

TEST(TetMesh, ToleranceScalesWithTheMesh) {
  const TetMesh small = build(cube_mesh(1.0));
  const TetMesh large = build(cube_mesh(1000.0));
  EXPECT_NEAR(large.tolerance() / small.tolerance(), 1000.0, 1e-6);
  EXPECT_NEAR(small.tolerance(), TetMesh::kRelativeTolerance * std::sqrt(3.0), 1e-15);
}

}  // namespace
}  // namespace hapticut
