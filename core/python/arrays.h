// Helpers of the bindings: numpy arrays in and out without a Python loop.
#pragma once

#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <vector>

#include "hapticut/vec3.h"

namespace hapticut::python {

namespace nb = nanobind;

using PointsIn = nb::ndarray<const double, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using TetsIn = nb::ndarray<const std::int32_t, nb::shape<-1, 4>, nb::c_contig, nb::device::cpu>;
using TrianglesIn =
    nb::ndarray<const std::int32_t, nb::shape<-1, 3>, nb::c_contig, nb::device::cpu>;
using IndicesIn = nb::ndarray<const std::int32_t, nb::shape<-1>, nb::c_contig, nb::device::cpu>;

// A new numpy array of the given shape that owns its memory.
template <class T>
nb::ndarray<nb::numpy, T> new_array(std::initializer_list<std::size_t> shape) {
  std::size_t size = 1;
  for (std::size_t s : shape) size *= s;
  T* data = new T[size == 0 ? 1 : size]();
  nb::capsule owner(data, [](void* p) noexcept { delete[] static_cast<T*>(p); });
  return nb::ndarray<nb::numpy, T>(data, shape.size(), shape.begin(), owner);
}

inline std::vector<Vec3> to_points(const PointsIn& a) {
  std::vector<Vec3> out(a.shape(0));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {a(i, 0), a(i, 1), a(i, 2)};
  return out;
}

inline std::vector<std::array<std::int32_t, 3>> to_triangles(const TrianglesIn& a) {
  std::vector<std::array<std::int32_t, 3>> out(a.shape(0));
  for (std::size_t t = 0; t < out.size(); ++t) out[t] = {a(t, 0), a(t, 1), a(t, 2)};
  return out;
}

inline nb::ndarray<nb::numpy, double> from_points(const std::vector<Vec3>& points) {
  auto out = new_array<double>({points.size(), 3});
  double* d = out.data();
  for (std::size_t i = 0; i < points.size(); ++i) {
    d[3 * i] = points[i].x;
    d[3 * i + 1] = points[i].y;
    d[3 * i + 2] = points[i].z;
  }
  return out;
}

inline nb::ndarray<nb::numpy, double> from_vec3(const Vec3& v) {
  auto out = new_array<double>({3});
  out.data()[0] = v.x;
  out.data()[1] = v.y;
  out.data()[2] = v.z;
  return out;
}

}  // namespace hapticut::python
