// The paper's measurement set-ups (Table 2) and the stress meshes of the
// invariant tests, generated in code so C++ tests, Python tests and the
// benchmarks use exactly the same geometry.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "hapticut/vec3.h"

namespace hapticut {

struct MeshData {
  std::vector<Vec3> vertices_mm;
  std::vector<std::array<std::int32_t, 4>> tets;
};

// Two tets sharing the face (0, 1, 2); tet 0 below (z < 0), tet 1 above.
MeshData two_tets_mesh(double size_mm = 10.0);
// One edge (vertices 0 and 1, along z) shared by `fan_size` tets around it:
// a bipyramid over a regular polygon of radius_mm, apexes at +-half_height_mm.
MeshData edge_fan_mesh(int fan_size = 12, double radius_mm = 10.0, double half_height_mm = 10.0);
// The icosahedron's centre (vertex 0) shared by its 20 tets.
MeshData icosahedron_mesh(double radius_mm = 10.0);
// The centre (vertex 0) of a geodesic ball: the icosahedron's 20 faces, each
// split into 4^subdivisions triangles (midpoints pushed onto the sphere of
// radius_mm), joined to the centre. Vertex 0 lies in 20 x 4^subdivisions tets
// (20, 80, 320, ...); subdivisions = 0 is icosahedron_mesh. 0 <= subdivisions <= 5.
MeshData vertex_fan_mesh(int subdivisions = 1, double radius_mm = 10.0);
// The centre (vertex 0) of a double cone: a regular ring of ring_size >= 3
// vertices of radius radius_mm around it in the plane z = 0, apexes 1 and 2 at
// z = -+half_height_mm. Vertex 0 lies in 2 x ring_size tets: vertex valences
// between the geodesic family's powers.
MeshData double_cone_mesh(int ring_size = 10, double radius_mm = 10.0,
                          double half_height_mm = 10.0);
// A cube of side size_mm split into 6 tets (Kuhn): 12 boundary triangles.
MeshData cube_mesh(double size_mm = 10.0);
// A box of nx x ny x nz cells, each split into 6 Kuhn tets (interior
// vertices in 24 tets), corners at `origin`; plane coordinates per axis may
// be uneven (thin layers). Vertices moved by up to jitter x spacing
// (a move that would flatten or invert a tet is shrunk).
MeshData grid_mesh(const std::vector<double>& xs, const std::vector<double>& ys,
                   const std::vector<double>& zs, double jitter = 0.0, std::uint64_t seed = 1);

}  // namespace hapticut
