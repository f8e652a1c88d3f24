// Force shading for Python: the per-vertex normals of a Space's rigid surface
// (ProxySet and Blade shade with them when settings.force_shading is on).
#include <nanobind/nanobind.h>

#include <cstdint>
#include <vector>

#include "arrays.h"
#include "hapticut/force_shading.h"
#include "hapticut/space.h"

namespace nb = nanobind;

namespace hapticut::python {

void bind_force_shading(nb::module_& m) {
  nb::class_<ForceShading>(m, "ForceShading",
                           "Per-vertex normals of a Space's rigid surface, for force shading.")
      .def(nb::init<const Space&>(), nb::arg("space"), nb::keep_alive<1, 2>())
      .def(
          "__init__",
          [](ForceShading* self, const Space& space, const PointsIn& vertices,
             const TrianglesIn& triangles) {
            new (self) ForceShading(space, to_points(vertices), to_triangles(triangles));
          },
          nb::arg("space"), nb::arg("source_vertices"), nb::arg("source_triangles"),
          nb::keep_alive<1, 2>(),
          "Vertex normals taken from the source surface the scene was built from.")
      .def_prop_ro(
          "vertex_normals",
          [](const ForceShading& s) {
            std::vector<Vec3> normals(s.vertex_count());
            for (std::int32_t v = 0; v < s.vertex_count(); ++v) normals[v] = s.vertex_normal(v);
            return from_points(normals);
          },
          "Unit normal out of the rigid region per mesh vertex; zero off the rigid surface.",
          nb::rv_policy::move)
      .def_prop_ro("memory_bytes", &ForceShading::memory_bytes, nb::rv_policy::move);
}

}  // namespace hapticut::python
