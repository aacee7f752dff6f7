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

// Up to kEntryGroup consecutive entries [g, min(g + kEntryGroup, end)) of a cell list: corners and
// triangle ids (−1 past the end), read before any is used, so a GPU thread has all their loads in
// flight at once instead of one entry's latency after another.
constexpr int kEntryGroup = 4;
template <typename T>
struct CellEntryGroup {
  Vec3<T> v[kEntryGroup][3];
  std::int32_t t[kEntryGroup];
};
template <typename T>
SINEW_HD_INLINE void load_cell_entries(const SurfaceView<T>& s, std::int32_t g, std::int32_t end,
                                       CellEntryGroup<T>& e) {
  for (int m = 0; m < kEntryGroup; ++m) {
    const bool in = g + m < end;
    const std::int32_t q = in ? g + m : g;
    e.t[m] = in ? s.cell_triangles[q] : -1;
    for (int c = 0; c < 3; ++c) e.v[m][c] = s.entry_corners[3 * q + c];
  }
}

// The grid cells [lo, hi] (inclusive, per axis) that the cube of half-side r around x touches,
// clipped to the grid. NaN in x or r (a diverging node, reported at the next sync point) gives the
// empty range [0, −1]: converting NaN to an integer is undefined (INT_MIN on the GPU).
template <typename T>
SINEW_HD_INLINE void cells_within(const SurfaceView<T>& s, const Vec3<T>& x, T r,
                                  std::int32_t lo[3], std::int32_t hi[3]) {
  for (int k = 0; k < 3; ++k) {
    const T dmax = T(s.dims[k]);
    T a = (x[k] - r - s.origin[k]) / s.cell;
    T b = (x[k] + r - s.origin[k]) / s.cell;
    a = a >= T(0) ? (a <= dmax ? a : dmax) : T(0);  // beyond the grid: empty range
    b = b >= T(0) ? (b <= dmax - T(1) ? b : dmax - T(1)) : T(-1);
    lo[k] = static_cast<std::int32_t>(a);
    hi[k] = static_cast<std::int32_t>(b);
  }
}

// Visits the cell entries of cells [lo, hi] that may lie within squared distance `bound` of x, in
// cell order, entries in list order: cells whose walls (axis by axis), then whose content box, lie
// farther are skipped, and entries whose triangle's box does. visit(t, corners) returns false to
// stop the walk (then this returns false). `bound` is read anew before every test, so a visitor may
// shrink it (the closest-point search does, as it finds closer triangles).
template <typename T, typename Visit>
SINEW_HD_INLINE bool visit_near_entries(const SurfaceView<T>& s, const Vec3<T>& x,
                                        const std::int32_t lo[3], const std::int32_t hi[3],
                                        const T& bound, Visit&& visit) {
  auto axis_gap = [&](int axis, std::int32_t idx) {
    const T c0 = s.origin[axis] + T(idx) * s.cell;
    const T v = x[axis];
    return v < c0 ? c0 - v : (v > c0 + s.cell ? v - c0 - s.cell : T(0));
  };
  for (std::int32_t k = lo[2]; k <= hi[2]; ++k) {
    const T gz = axis_gap(2, k);
    if (gz * gz > bound) continue;
    for (std::int32_t j = lo[1]; j <= hi[1]; ++j) {
      const T gy = axis_gap(1, j);
      if (gz * gz + gy * gy > bound) continue;
      for (std::int32_t i = lo[0]; i <= hi[0]; ++i) {
        const T gx = axis_gap(0, i);
        if (gz * gz + gy * gy + gx * gx > bound) continue;
        const std::int32_t c = (k * s.dims[1] + j) * s.dims[0] + i;
        // The cell's content box: skip a cell whose triangles cannot reach below the bound.
        // (Its list range is read alongside: independent loads in flight together.)
        const Vec3<T> cl = s.cell_boxes[2 * c], ch = s.cell_boxes[2 * c + 1];
        const std::int32_t q0 = s.cell_offsets[c], q1 = s.cell_offsets[c + 1];
        if (box_distance2(x, cl, ch) > bound) continue;
        // Entries in groups (cell_entry_group): each entry's corners and id are one read, the box
        // bound first, then the visit on the same registers, entries in list order.
        for (std::int32_t g = q0; g < q1; g += kEntryGroup) {
          CellEntryGroup<T> e;
          load_cell_entries(s, g, q1, e);
          for (int m = 0; m < kEntryGroup; ++m) {
            if (e.t[m] < 0) continue;
            Vec3<T> bl, bh;
            triangle_box(e.v[m][0], e.v[m][1], e.v[m][2], bl, bh);
            if (box_distance2(x, bl, bh) > bound) continue;
            if (!visit(e.t[m], e.v[m])) return false;
          }
        }
      }
    }
  }
  return true;
}

// Closest point of the surface to x; `triangle` in: warm start (or −1), out: closest triangle.
// Among triangles at exactly the same distance the warm start wins, then (kLowestIdTies false) the
// first met in cell order, or (kLowestIdTies true) the lowest triangle id: a rule that does not
// depend on the order of visiting, so the candidate-list query below gives the same triangle.
template <typename T, bool kLowestIdTies>
SINEW_HD_INLINE Vec3<T> closest_surface_search(const SurfaceView<T>& s, const Vec3<T>& x,
                                               std::int32_t& triangle) {
  Vec3<T> best_p{T(0), T(0), T(0)};
  T best = T(0);
  std::int32_t best_t = -1;
  const std::int32_t warm = triangle >= 0 && triangle < s.triangle_count ? triangle : 0;
  if (triangle >= 0 && triangle < s.triangle_count) {
    best = triangle_distance2(s, triangle, x, best_p);
    best_t = triangle;
  } else {
    // No warm start: the first triangle bounds the search (exact, just slower once).
    best = triangle_distance2(s, 0, x, best_p);
    best_t = 0;
  }
  std::int32_t lo[3], hi[3];
  cells_within(s, x, std::sqrt(best), lo, hi);
  visit_near_entries(s, x, lo, hi, best, [&](std::int32_t t, const Vec3<T>(&v)[3]) {
    if (t == best_t) return true;
    const Vec3<T> p = physics::closest_point_on_triangle(x, v[0], v[1], v[2]);
    const T d = squared_norm(x - p);
    if (d < best || (kLowestIdTies && d == best && best_t != warm && t < best_t)) {
      best = d;
      best_p = p;
      best_t = t;
    }
    return true;
  });
  triangle = best_t;
  return best_p;
}

template <typename T>
SINEW_HD_INLINE Vec3<T> closest_surface_point(const SurfaceView<T>& s, const Vec3<T>& x,
                                              std::int32_t& triangle) {
  return closest_surface_search<T, false>(s, x, triangle);
}

// Candidate lists (Verlet lists with a skin, exact): at the anchor x_s, with closest distance d1,
// list every triangle within d1 + 2 s of x_s (list_surface_candidates). While the node stays
// within s of x_s, its closest triangle is in the list: for |x − x_s| ≤ s, the closest triangle T* at x has
// dist(x, T*) ≤ dist(x, T1) ≤ d1 + s, so dist(x_s, T*) ≤ d1 + 2 s. Only the listed triangles are
// then tested, with the lowest-id tie rule of closest_surface_search<T, true> (warm start first),
// so both paths return the same triangle. The move test uses s (1 − 1e-3): the margin covers float
// round-off in the listed distances (s is a fraction of a cell, far above it).
//
// Each entry also keeps D_j = dist(x_s, T_j), the list sorted by it. At x with δ = |x − x_s|,
// dist(x, T_j) ≥ D_j − δ, so once the warm start (distance d_w) is tested, every entry with
// D_j > d_w + δ + μ is strictly farther than it, can neither win nor tie, and ends the walk: most
// nodes test their warm start only (μ: closest_listed_point).

// Per triangle its three corners (3 per triangle), in the query's scalar, for the listed tests.
template <typename T>
std::vector<Vec3<T>> triangle_corner_list(
    const std::vector<Vec3<T>>& vertices,
    const std::vector<std::array<std::int32_t, 3>>& triangles) {
  std::vector<Vec3<T>> c(3 * triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (std::size_t k = 0; k < 3; ++k) c[3 * t + k] = vertices[std::size_t(triangles[t][k])];
  return c;
}

// The candidate list of x in one grid walk: every triangle within d1 + 2 s of x (d1: the distance
// from x to the surface, s: skin) into list[j · stride] with its distance from x in
// distance[j · stride], j < kCapacity, each once, sorted by (distance, id); returns their count, or
// −1 when more than kCapacity lie within d1 + 2 s (no list: the node searches fully). `triangle`
// in: a warm start (any id; invalid: triangle 0), out: the closest triangle (lowest id among equal
// distances; also on overflow).
//
// The walk's radius starts at d_w + 2 s (d_w: the warm start's distance, ≥ d1) and shrinks to
// d_b + 2 s as closer triangles are found (d_b: the closest so far), so one walk both finds d1 and
// lists, where a search within d_w and then a walk within d1 + 2 s would visit the near cells
// twice. Entries listed while the radius was larger are dropped at the end (d > d1 + 2 s). A full
// list keeps its kCapacity closest entries and remembers the closest it dropped: the list
// overflowed only if that one lies within the final d1 + 2 s. The list is built in the caller's
// own (thread-local) arrays and written out once: on the GPU its insertions then stay in L1
// instead of waiting on the strided global list entry by entry.
template <int kCapacity, typename T>
SINEW_HD_INLINE std::int32_t list_surface_candidates(const SurfaceView<T>& s, const Vec3<T>& x,
                                                     T skin, std::int32_t& triangle,
                                                     std::int32_t* list, T* distance,
                                                     std::int64_t stride) {
  const std::int32_t warm = triangle >= 0 && triangle < s.triangle_count ? triangle : 0;
  Vec3<T> p;
  T radius = std::sqrt(triangle_distance2(s, warm, x, p)) + T(2) * skin;
  T r2 = radius * radius;
  std::int32_t lo[3], hi[3];
  cells_within(s, x, radius, lo, hi);
  // The list being built, entries [0, count) set. (Read through pointers: nvcc's used-before-set
  // check does not see that the full-list branch runs only once count = kCapacity.)
  std::int32_t id_store[kCapacity];
  T distance_store[kCapacity];
  std::int32_t* const ids = id_store;
  T* const ds = distance_store;
  std::int32_t count = 0;
  bool dropped = false;
  T dropped_distance = T(0);  // the closest dropped entry's distance (when `dropped`)
  auto drop = [&](T d) {
    dropped_distance = dropped && dropped_distance < d ? dropped_distance : d;
    dropped = true;
  };
  visit_near_entries(s, x, lo, hi, r2, [&](std::int32_t t, const Vec3<T>(&v)[3]) {
    const Vec3<T> q = physics::closest_point_on_triangle(x, v[0], v[1], v[2]);
    const T d2 = squared_norm(x - q);
    if (d2 > r2) return true;
    for (std::int32_t n = 0; n < count; ++n)
      if (ids[n] == t) return true;
    const T d = std::sqrt(d2);
    if (count == kCapacity) {  // full: the farther of this entry and the last one goes
      const T last = ds[kCapacity - 1];
      if (d > last || (d == last && t > ids[kCapacity - 1])) {
        drop(d);
        return true;
      }
      drop(last);
      --count;
    }
    // Insertion into the sorted list (lists hold a few entries).
    std::int32_t n = count++;
    for (; n > 0; --n) {
      if (ds[n - 1] < d || (ds[n - 1] == d && ids[n - 1] < t)) break;
      ids[n] = ids[n - 1];
      ds[n] = ds[n - 1];
    }
    ids[n] = t;
    ds[n] = d;
    if (n == 0) {  // a new closest: the radius shrinks to d + 2 s
      radius = d + T(2) * skin;
      r2 = radius * radius;
    }
    return true;
  });
  // The warm start lies within the first radius, so the list holds at least one entry, the first
  // the closest triangle (never dropped: a full list drops its farthest). Empty only for a NaN x
  // (cells_within: no cells): no list.
  if (count == 0) return 0;
  triangle = ids[0];
  while (count > 0 && ds[count - 1] > radius) --count;
  if (dropped && dropped_distance <= radius) return -1;
  for (std::int32_t n = 0; n < count; ++n) {
    list[n * stride] = ids[n];
    distance[n * stride] = ds[n];
  }
  return count;
}

// Entries m0, m0 + 1 of a list (list[j · stride], distance[j · stride]; id −1 from `count` on):
// closest_listed_point reads a list two entries at a time.
template <typename T>
struct ListedGroup {
  static constexpr int kSize = 2;
  std::int32_t id[kSize];
  T distance[kSize];
};

template <typename T>
SINEW_HD_INLINE ListedGroup<T> load_listed_group(const std::int32_t* list, const T* distance,
                                                 std::int64_t stride, std::int32_t count,
                                                 std::int32_t m0) {
  ListedGroup<T> g;
  for (int j = 0; j < ListedGroup<T>::kSize; ++j) {
    const bool in = m0 + j < count;
    g.id[j] = in ? list[(m0 + j) * stride] : -1;
    g.distance[j] = in ? distance[(m0 + j) * stride] : T(0);
  }
  return g;
}

// Closest point to x of the listed triangles (count ≥ 1, sorted as list_surface_candidates
// leaves them) and the warm start, with the rule of closest_surface_search<T, true>: strictly
// closer wins; on equal distance the warm start, then the lowest id. `triangle` in: the warm start
// (a valid triangle id; warm: its corners), out: the closest triangle. corners:
// triangle_corner_list. moved: δ, the distance of x from the list's anchor. margin: μ > 0, covering
// the float round-off of D_j, δ and the tested distances (callers give s/16: far above round-off,
// far below the gaps that cull). first: its entries 0 and 1 (load_listed_group), which a caller
// may have loaded ahead.
template <typename T>
SINEW_HD_INLINE Vec3<T> closest_listed_point(const Vec3<T>* corners, const Vec3<T> (&warm)[3],
                                             const std::int32_t* list, const T* distance,
                                             std::int64_t stride, std::int32_t count,
                                             const ListedGroup<T>& first, const Vec3<T>& x, T moved,
                                             T margin, std::int32_t& triangle) {
  const std::int32_t warm_t = triangle;
  // Two entries at a time: their ids and distances (the first two read before the warm start's
  // test: no load waits on it), then their corners, are loads in flight together.
  constexpr int kGroup = ListedGroup<T>::kSize;
  std::int32_t ts[kGroup];
  T ds[kGroup];
  auto take_group = [&](const ListedGroup<T>& g) {
    for (int j = 0; j < kGroup; ++j) {
      ts[j] = g.id[j];
      ds[j] = g.distance[j];
    }
  };
  take_group(first);
  Vec3<T> best_p = physics::closest_point_on_triangle(x, warm[0], warm[1], warm[2]);
  T best = squared_norm(x - best_p);
  std::int32_t best_t = warm_t;
  const T bound = std::sqrt(best) + moved + margin;
  for (std::int32_t m0 = 0; m0 < count; m0 += kGroup) {
    if (m0 > 0) take_group(load_listed_group(list, distance, stride, count, m0));
    if (ds[0] > bound) break;  // this entry and all after it are strictly farther
    Vec3<T> c[kGroup][3];
    for (int j = 0; j < kGroup; ++j) {
      if (ts[j] == warm_t || ds[j] > bound) ts[j] = -1;
      for (int v = 0; v < 3; ++v) c[j][v] = ts[j] >= 0 ? corners[3 * ts[j] + v] : x;
    }
    for (int j = 0; j < kGroup; ++j) {
      const std::int32_t t = ts[j];
      if (t < 0) continue;
      const Vec3<T> p = physics::closest_point_on_triangle(x, c[j][0], c[j][1], c[j][2]);
      const T d = squared_norm(x - p);
      if (d < best || (d == best && best_t != warm_t && t < best_t)) {
        best = d;
        best_p = p;
        best_t = t;
      }
    }
  }
  triangle = best_t;
  return best_p;
}

template <typename T>
SINEW_HD_INLINE Vec3<T> closest_listed_point(const Vec3<T>* corners, const Vec3<T> (&warm)[3],
                                             const std::int32_t* list, const T* distance,
                                             std::int64_t stride, std::int32_t count,
                                             const Vec3<T>& x, T moved, T margin,
                                             std::int32_t& triangle) {
  return closest_listed_point(corners, warm, list, distance, stride, count,
                              load_listed_group(list, distance, stride, count, 0), x, moved, margin,
                              triangle);
}

}  // namespace sinew::simulator
