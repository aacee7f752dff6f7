#pragma once
// Sliding candidate lists (Verlet lists with a skin, exact: sliding_grid.hpp) and the sliding
// constraint of one node, written once for both engines: the CPU runs them inline in its constraint
// pass (engine/cpu_engine.cpp), the GPU in its constraint kernel and, ahead of a step, in its list
// refresh kernel (cuda/constraint_kernels.cuh). docs/cuda-backend.md, "Sliding", has the design and
// its measurements.
#include <cmath>
#include <cstdint>

#include "sinew/common/host_device.hpp"
#include "sinew/common/math.hpp"
#include "sinew/simulator/passes/sliding_grid.hpp"
#include "sinew/simulator/passes/step_status.hpp"
#include "sinew/simulator/physics/sliding.hpp"

namespace sinew::simulator {

// Default skin s of the candidate lists, in grid cells of the surface (about mean edges): a node
// tests only its listed triangles until it moves more than s. Exact for any s > 0 (larger: longer
// lists, rarer searches; docs/performance.md has the sweep).
inline constexpr double kDefaultSlidingSkin = 0.05;

// Sliding: per surface its query view, per-triangle corners and skin (sliding_grid.hpp).
template <typename T>
struct SlideSurface {
  SurfaceView<T> view;
  const Vec3<T>* corners;  // triangle_corner_list: 3 per triangle
  T skin;                  // s of the candidate lists (m)
};

// List capacity per sliding node (overflow: full search each step). The face-scale skull lists
// 3.6 triangles per node on average (at most 10) with the default skin, 12.5 (at most 22) with 0.25.
constexpr int kCandidates = 32;

// Per sliding node k: node id, surface, rest distance, closest triangle of the last step (the warm
// start of the tie rule, as the CPU's), the warm start of the grid searches (written by list
// refreshes only, so a refresh running beside a step never touches what the step reads), and its
// candidate list: count (−1: none, search fully), anchor x_s, ids at list[j · count + k] and their
// distances from x_s at list_distance[j · count + k] (sorted: list_surface_candidates).
template <typename T>
struct SlideData {
  const std::int32_t* node;
  const std::int32_t* surface;
  const T* distance;
  std::int32_t* triangle;
  std::int32_t* search_triangle;
  std::int32_t* list_count;
  Vec3<T>* anchor;
  std::int32_t* list;
  T* list_distance;
  const SlideSurface<T>* surfaces;
  std::int32_t count;
  StepStatus* status;  // slide_miss (refresh ahead)
};

// Sliding node k at position x: while x is within s (1 − 1e-3) of the anchor of its list, the
// list holds its closest triangle (sliding_grid.hpp) and nothing is done; otherwise one grid walk
// (list_surface_candidates, warm-started from search_triangle[k], where it leaves the closest
// triangle) re-lists the triangles within d1 + 2 s and moves the anchor to x (list count −1 when
// more than kCandidates: the node then searches fully). `reach` (≤ 1): the fraction of s within
// which the anchor is kept (½ when refreshing ahead of the step, from u(n), so that u(n+1) still
// lies within s of the anchor).
template <typename T>
SINEW_HD_INLINE void refresh_slide_list(const SlideData<T>& d, std::int32_t k, const Vec3<T>& x,
                                        T reach) {
  const SlideSurface<T>& sf = d.surfaces[d.surface[k]];
  const T move = sf.skin * T(0.999) * reach;
  if (d.list_count[k] > 0 && squared_norm(x - d.anchor[k]) <= move * move) return;
  std::int32_t t = d.search_triangle[k];
  d.list_count[k] = list_surface_candidates<kCandidates>(sf.view, x, sf.skin, t, d.list + k,
                                                         d.list_distance + k, d.count);
  d.search_triangle[k] = t;
  d.anchor[k] = x;
}

// Sliding node k at displacement u: the closest triangle among its listed ones and its warm start
// (closest_listed_point; the one the search found, when its list overflowed), then x' = p + d n
// (physics::project_to_rest_distance), as physics::slide_node does. Returns the new
// displacement. kRefresh: refresh_slide_list at x first (the grid search inline when needed).
// Otherwise slide_refresh_kernel refreshed the list from u(n), ahead of the step: if x is not
// within s of its anchor (or the list overflowed) the list may not hold the closest triangle, so
// the node raises status->slide_miss and the host replays the batch with kRefresh (the result
// computed here is then discarded).
//
// SlideStart: what slide_entry reads of entry k that the step's kernels before it do not write
// (the closest triangle of the last step was written by the previous step's constraints), so a
// programmatic launch loads it before its wait: the surface, rest distance and warm start (its id,
// corners and normal); with `lists` (no list refresh in this step: lists_ready) also the list's
// count, anchor and first entries.
template <typename T>
struct SlideStart {
  const SlideSurface<T>* surface;
  T distance;
  std::int32_t triangle;
  Vec3<T> warm[3];
  Vec3<T> normal;
  bool lists;
  std::int32_t listed;
  Vec3<T> anchor;
  ListedGroup<T> first;
};

template <typename T>
SINEW_HD_INLINE SlideStart<T> slide_start(const SlideData<T>& d, std::int32_t k, bool lists_ready) {
  SlideStart<T> s;
  s.surface = d.surfaces + d.surface[k];
  s.distance = d.distance[k];
  const std::int32_t t = d.triangle[k];
  s.triangle = t;
  for (int c = 0; c < 3; ++c) s.warm[c] = s.surface->corners[3 * t + c];
  s.normal = s.surface->view.normals[t];
  s.lists = lists_ready;
  if (lists_ready) {
    s.listed = d.list_count[k];
    s.anchor = d.anchor[k];
    s.first = load_listed_group(d.list + k, d.list_distance + k, d.count, s.listed, 0);
  }
  return s;
}

template <typename T, bool kRefresh>
SINEW_HD_INLINE Vec3<T> slide_entry(const SlideData<T>& d, std::int32_t k,
                                    const SlideStart<T>& start, const Vec3<T>& rest,
                                    const Vec3<T>& u) {
  const Vec3<T> x = rest + u;
  const SlideSurface<T>& sf = *start.surface;
  if constexpr (kRefresh) refresh_slide_list(d, k, x, T(1));  // start.lists is false here
  const std::int32_t listed = start.lists ? start.listed : d.list_count[k];
  const Vec3<T> anchor = start.lists ? start.anchor : d.anchor[k];
  if constexpr (!kRefresh) {
    const T move = sf.skin * T(0.999);
    if (!(listed > 0 && squared_norm(x - anchor) <= move * move)) d.status->slide_miss = 1;
  }
  std::int32_t t = start.triangle;
  Vec3<T> p;
  if (listed > 0) {
    const T moved = std::sqrt(squared_norm(x - anchor));
    const ListedGroup<T> first =
        start.lists ? start.first
                    : load_listed_group(d.list + k, d.list_distance + k, d.count, listed, 0);
    p = closest_listed_point(sf.corners, start.warm, d.list + k, d.list_distance + k, d.count,
                             listed, first, x, moved, sf.skin * T(0.0625), t);
  } else if constexpr (kRefresh) {  // overflow: the grid search, warm-started as the CPU's
    p = closest_surface_search<T, true>(sf.view, x, t);
  } else {  // overflow without a search: a miss (raised above), replayed; any finite point
    p = physics::closest_point_on_triangle(x, start.warm[0], start.warm[1], start.warm[2]);
  }
  d.triangle[k] = t;
  const Vec3<T> normal = t == start.triangle ? start.normal : sf.view.normals[t];
  return physics::project_to_rest_distance(x, p, normal, start.distance) - rest;
}

}  // namespace sinew::simulator
