// hapticut._core: the engine for Python (authoring, tests, benchmarks).
#include <nanobind/nanobind.h>

namespace nb = nanobind;

namespace hapticut::python {
void bind_mesh(nb::module_& m);
void bind_proxy(nb::module_& m);
void bind_benchmarks(nb::module_& m);
void bind_force_shading(nb::module_& m);
}  // namespace hapticut::python

void bind_scene(nb::module_& m);

NB_MODULE(_core, m) {
  m.doc() = "Hapticut engine: tet meshes, materials, proxies and blades (C++).";
  // Tuned for the building machine (-march=native, HAPTICUT_NATIVE=ON) or portable.
  m.attr("BUILT_NATIVE") = static_cast<bool>(HAPTICUT_BUILT_NATIVE);
  hapticut::python::bind_mesh(m);
  hapticut::python::bind_proxy(m);
  hapticut::python::bind_benchmarks(m);
  hapticut::python::bind_force_shading(m);
  bind_scene(m);
}
