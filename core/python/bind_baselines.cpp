// Bindings of the baseline methods (voxel proxy, surface god-object).
#include <nanobind/nanobind.h>

namespace nb = nanobind;

void bind_baselines(nb::module_& m) { (void)m; }
