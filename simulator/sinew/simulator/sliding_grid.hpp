#pragma once
// The acceleration structure of a static sliding surface: a uniform grid over its bounding box
// whose cells list the triangles whose bounding boxes overlap them. Built once (surfaces never
// move); queried every step for every sliding node with a warm start.
//
// Query (closest_surface_point): d_w = distance from x to the warm-start triangle (the node's
// previous closest one); every triangle closer than d_w has its bounding box inside the cube
// [x − d_w, x + d_w], so only the cells overlapping that cube are searched. The result is exact
// (the true closest triangle), and cheap when the node moved little. Ties keep the first triangle
// met in cell order, which is deterministic.
#include <array>
#include <cstdint>
#include <vector>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/physics/sliding.hpp"

namespace sinew::simulator {

struct SurfaceGrid {
  std::array<double, 3> origin{0, 0, 0};  // m, min corner
  double cell = 1;                        // m, cell side
  std::array<std::int32_t, 3> dims{1, 1, 1};
  std::vector<std::int32_t> cell_offsets;  // cells + 1 (CSR)
  std::vector<std::int32_t> cell_triangles;
  std::size_t bytes() const { return (cell_offsets.size() + cell_triangles.size()) * 4; }
};

// Cell side = 1.5 × the mean edge length, at least (bounding-box volume / (64 · triangles))^(1/3).
SurfaceGrid build_surface_grid(const std::vector<std::array<double, 3>>& vertices,
                               const std::vector<std::array<std::int32_t, 3>>& triangles);

// A plain-pointer view for the query (host now, device later).
template <typename T>
struct SurfaceView {
  const Vec3<T>* vertices;
  const std::array<std::int32_t, 3>* triangles;
  const Vec3<T>* normals;  // unit outward normal per triangle
  std::int32_t triangle_count;
  const std::int32_t* cell_offsets;
  const std::int32_t* cell_triangles;
  T origin[3];
  T cell;
  std::int32_t dims[3];
};

template <typename T>
SINEW_HD_INLINE T triangle_distance2(const SurfaceView<T>& s, std::int32_t t, const Vec3<T>& x,
                                     Vec3<T>& p) {
  const auto& tri = s.triangles[t];
  p = physics::closest_point_on_triangle(x, s.vertices[tri[0]], s.vertices[tri[1]],
                                         s.vertices[tri[2]]);
  return squared_norm(x - p);
}

// Closest point of the surface to x; `triangle` in: warm start (or −1), out: closest triangle.
template <typename T>
SINEW_HD_INLINE Vec3<T> closest_surface_point(const SurfaceView<T>& s, const Vec3<T>& x,
                                              std::int32_t& triangle) {
  Vec3<T> best_p{T(0), T(0), T(0)};
  T best = T(0);
  std::int32_t best_t = -1;
  if (triangle >= 0 && triangle < s.triangle_count) {
    best = triangle_distance2(s, triangle, x, best_p);
    best_t = triangle;
  } else {
    // No warm start: the first triangle bounds the search (exact, just slower once).
    best = triangle_distance2(s, 0, x, best_p);
    best_t = 0;
  }
  const T r = std::sqrt(best);
  std::int32_t lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    const T dmax = T(s.dims[k]);
    T a = (x[k] - r - s.origin[k]) / s.cell;
    T b = (x[k] + r - s.origin[k]) / s.cell;
    a = a < T(0) ? T(0) : (a > dmax ? dmax : a);  // dims: empty range
    b = b < T(0) ? T(-1) : (b > dmax - T(1) ? dmax - T(1) : b);
    const std::int32_t l = static_cast<std::int32_t>(a);
    const std::int32_t h = static_cast<std::int32_t>(b);
    lo[k] = l;
    hi[k] = h;
  }
  // Cells farther from x than the best distance so far cannot hold a closer triangle.
  auto axis_gap = [&](int axis, std::int32_t idx) {
    const T c0 = s.origin[axis] + T(idx) * s.cell;
    const T v = x[axis];
    return v < c0 ? c0 - v : (v > c0 + s.cell ? v - c0 - s.cell : T(0));
  };
  for (std::int32_t k = lo[2]; k <= hi[2]; ++k) {
    const T gz = axis_gap(2, k);
    if (gz * gz > best) continue;
    for (std::int32_t j = lo[1]; j <= hi[1]; ++j) {
      const T gy = axis_gap(1, j);
      if (gz * gz + gy * gy > best) continue;
      for (std::int32_t i = lo[0]; i <= hi[0]; ++i) {
        const T gx = axis_gap(0, i);
        if (gz * gz + gy * gy + gx * gx > best) continue;
        const std::int32_t c = (k * s.dims[1] + j) * s.dims[0] + i;
        for (std::int32_t q = s.cell_offsets[c]; q < s.cell_offsets[c + 1]; ++q) {
          const std::int32_t t = s.cell_triangles[q];
          if (t == best_t) continue;
          Vec3<T> p;
          const T d = triangle_distance2(s, t, x, p);
          if (d < best) {
            best = d;
            best_p = p;
            best_t = t;
          }
        }
      }
    }
  }
  triangle = best_t;
  return best_p;
}

}  // namespace sinew::simulator
