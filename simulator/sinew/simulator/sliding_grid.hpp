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
//
// Two bounding-box culls make it cheap when the node sits about one edge off the surface (the
// search cube then spans several cells): each cell carries the box of its content (its triangles'
// boxes clipped to the cell), and each cell entry its triangle's corners inline (SurfaceLists), so
// an entry costs one read with no dependent triangle/vertex loads. The squared distance from x to
// a box is a lower bound of the squared distance to everything in it, so a cell whose box, or an
// entry whose triangle's box, is farther than the best distance so far is skipped (the cell without
// reading its list, the entry without the exact closest-point test). The result is the same as
// testing every listed triangle (first minimum in cell order), up to round-off in comparing
// near-equal distances.
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

// Cell side = the mean edge length, at least (bounding-box volume / (64 · triangles))^(1/3).
SurfaceGrid build_surface_grid(const std::vector<std::array<double, 3>>& vertices,
                               const std::vector<std::array<std::int32_t, 3>>& triangles);

// The cell lists as the query reads them, in its scalar T (from the vertices as the query sees
// them, so a box holds its triangle exactly):
//   corners: per entry of grid.cell_triangles, its triangle's three vertices (3 per entry), so the
//            query reads one entry with one load and no dependent triangle/vertex loads;
//   cell:    per cell, 2 (min, max): the union of its triangles' boxes clipped to the cell widened
//            by 1e-3 cells (the margin covers the float rounding of vertices and walls against the
//            double grid), so it holds every triangle point in the cell. Empty cells: inverted.
template <typename T>
struct SurfaceLists {
  std::vector<Vec3<T>> corners;
  std::vector<Vec3<T>> cell;
};

// Component-wise bounding box of a triangle.
template <typename T>
SINEW_HD_INLINE void triangle_box(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c, Vec3<T>& lo,
                                  Vec3<T>& hi) {
  for (int k = 0; k < 3; ++k) {
    const T m = a[k] < b[k] ? a[k] : b[k];
    const T n = a[k] > b[k] ? a[k] : b[k];
    lo[k] = m < c[k] ? m : c[k];
    hi[k] = n > c[k] ? n : c[k];
  }
}

template <typename T>
SurfaceLists<T> make_surface_lists(const SurfaceGrid& grid, const std::vector<Vec3<T>>& vertices,
                                   const std::vector<std::array<std::int32_t, 3>>& triangles) {
  SurfaceLists<T> l;
  l.corners.resize(3 * grid.cell_triangles.size());
  for (std::size_t q = 0; q < grid.cell_triangles.size(); ++q) {
    const auto& tri = triangles[std::size_t(grid.cell_triangles[q])];
    for (std::size_t c = 0; c < 3; ++c) l.corners[3 * q + c] = vertices[std::size_t(tri[c])];
  }
  const std::size_t cells = grid.cell_offsets.size() - 1;
  l.cell.resize(2 * cells);
  const double margin = 1e-3 * grid.cell;
  for (std::size_t c = 0; c < cells; ++c) {
    const std::size_t idx[3] = {c % std::size_t(grid.dims[0]),
                                (c / std::size_t(grid.dims[0])) % std::size_t(grid.dims[1]),
                                c / (std::size_t(grid.dims[0]) * std::size_t(grid.dims[1]))};
    Vec3<T> lo, hi;
    for (int k = 0; k < 3; ++k) {
      lo[k] = T(1e30);
      hi[k] = T(-1e30);
    }
    for (auto q = std::size_t(grid.cell_offsets[c]); q < std::size_t(grid.cell_offsets[c + 1]);
         ++q) {
      Vec3<T> a, b;
      triangle_box(l.corners[3 * q], l.corners[3 * q + 1], l.corners[3 * q + 2], a, b);
      for (int k = 0; k < 3; ++k) {
        lo[k] = a[k] < lo[k] ? a[k] : lo[k];
        hi[k] = b[k] > hi[k] ? b[k] : hi[k];
      }
    }
    for (int k = 0; k < 3; ++k) {
      const double w = grid.origin[std::size_t(k)] + double(idx[k]) * grid.cell;
      const T wlo = T(w - margin), whi = T(w + grid.cell + margin);
      lo[k] = wlo > lo[k] ? wlo : lo[k];
      hi[k] = whi < hi[k] ? whi : hi[k];
    }
    l.cell[2 * c] = lo;
    l.cell[2 * c + 1] = hi;
  }
  return l;
}

// Squared distance from x to the box (lo, hi): 0 inside.
template <typename T>
SINEW_HD_INLINE T box_distance2(const Vec3<T>& x, const Vec3<T>& lo, const Vec3<T>& hi) {
  T d2 = T(0);
  for (int a = 0; a < 3; ++a) {
    const T v = x[a];
    const T g = v < lo[a] ? lo[a] - v : (v > hi[a] ? v - hi[a] : T(0));
    d2 += g * g;
  }
  return d2;
}

// A plain-pointer view for the query (host now, device later).
template <typename T>
struct SurfaceView {
  const Vec3<T>* vertices;
  const std::array<std::int32_t, 3>* triangles;
  const Vec3<T>* normals;  // unit outward normal per triangle
  std::int32_t triangle_count;
  const std::int32_t* cell_offsets;
  const std::int32_t* cell_triangles;
  const Vec3<T>* entry_corners;  // SurfaceLists::corners (3 per entry of cell_triangles)
  const Vec3<T>* cell_boxes;     // SurfaceLists::cell (2 per cell)
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
        // The cell's content box: skip a cell whose triangles cannot reach below the best so far.
        if (box_distance2(x, s.cell_boxes[2 * c], s.cell_boxes[2 * c + 1]) > best) continue;
        for (std::int32_t q = s.cell_offsets[c]; q < s.cell_offsets[c + 1]; ++q) {
          // One read per entry (its corners; the id alongside): the box bound first, then the
          // exact test on the same registers, so a divergent exact test costs no further loads.
          const Vec3<T> va = s.entry_corners[3 * q], vb = s.entry_corners[3 * q + 1],
                        vc = s.entry_corners[3 * q + 2];
          const std::int32_t t = s.cell_triangles[q];
          Vec3<T> bl, bh;
          triangle_box(va, vb, vc, bl, bh);
          if (box_distance2(x, bl, bh) > best) continue;
          if (t == best_t) continue;
          const Vec3<T> p = physics::closest_point_on_triangle(x, va, vb, vc);
          const T d = squared_norm(x - p);
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
