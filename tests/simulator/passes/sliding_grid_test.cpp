// The sliding nodes' candidate lists (sliding_grid.hpp) against every triangle, and the listed
// query against the full grid search it stands in for: the same closest triangle and the same
// closest point, bit for bit, in float and double, for nodes anywhere within the skin of their
// list's anchor, with ties (nodes above the vertices and edges of a flat patch) and with the
// distance cull of closest_listed_point doing its work.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <utility>
#include <vector>

#include "sinew/simulator/passes/sliding_grid.hpp"

namespace sinew::simulator {
namespace {

// A 40 × 30 vertex sheet of spacing h: flat for x < 20 h (exact ties above its vertices and
// edges), a smooth bump field beyond; two triangles per quad.
struct Sheet {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  double h = 1e-3;
  int nx = 40, ny = 30;
};

Sheet make_sheet() {
  Sheet s;
  for (int j = 0; j < s.ny; ++j)
    for (int i = 0; i < s.nx; ++i) {
      const double x = i * s.h, y = j * s.h;
      const double z = i < 20 ? 0.0 : 0.8 * s.h * std::sin(0.7 * (i - 20)) * std::cos(0.5 * j);
      s.vertices.push_back({x, y, z});
    }
  auto id = [&](int i, int j) { return std::int32_t(j * s.nx + i); };
  for (int j = 0; j + 1 < s.ny; ++j)
    for (int i = 0; i + 1 < s.nx; ++i) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

template <typename T>
void expect_listed_query_is_exact(const char* name) {
  const Sheet sheet = make_sheet();
  const SurfaceGrid grid = build_surface_grid(sheet.vertices, sheet.triangles);
  std::vector<Vec3<T>> v;
  for (const auto& p : sheet.vertices) v.push_back({T(p[0]), T(p[1]), T(p[2])});
  std::vector<Vec3<T>> normals;
  for (const auto& t : sheet.triangles)
    normals.push_back(
        physics::triangle_normal(v[std::size_t(t[0])], v[std::size_t(t[1])], v[std::size_t(t[2])]));
  const SurfaceLists<T> lists = make_surface_lists(grid, v, sheet.triangles);
  const std::vector<Vec3<T>> corners = triangle_corner_list(v, sheet.triangles);
  SurfaceView<T> view{v.data(),
                      sheet.triangles.data(),
                      normals.data(),
                      std::int32_t(sheet.triangles.size()),
                      grid.cell_offsets.data(),
                      grid.cell_triangles.data(),
                      lists.corners.data(),
                      lists.cell.data(),
                      {},
                      T(grid.cell),
                      {}};
  for (int k = 0; k < 3; ++k) {
    view.origin[k] = T(grid.origin[std::size_t(k)]);
    view.dims[k] = grid.dims[std::size_t(k)];
  }

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double h = sheet.h;
  constexpr std::int32_t kCapacity = 64;
  std::int32_t list[kCapacity];
  T distance[kCapacity];
  long queries = 0, entries = 0, culled = 0, ties = 0, brute_checked = 0, small_overflows = 0;
  for (double skin_cells : {0.05, 0.25, 0.5}) {
    const T skin = T(skin_cells * grid.cell);
    for (int trial = 0; trial < 3000; ++trial) {
      // The anchor: above the flat patch on its lattice points, edges and centres (ties) in a
      // third of the trials, anywhere above the sheet otherwise.
      Vec3<T> anchor;
      if (trial % 3 == 0) {
        const int i = 2 + int(unit(rng) * 15), j = 2 + int(unit(rng) * 25);
        const double fx = 0.5 * double(int(unit(rng) * 3)), fy = 0.5 * double(int(unit(rng) * 3));
        anchor = {T((i + fx) * h), T((j + fy) * h), T((0.25 + 2 * unit(rng)) * h)};
      } else {
        anchor = {T((1 + 37 * unit(rng)) * h), T((1 + 27 * unit(rng)) * h),
                  T((0.25 + 2 * unit(rng)) * h)};
      }
      std::int32_t t_anchor = -1;
      const Vec3<T> p_anchor = closest_surface_search<T, true>(view, anchor, t_anchor);
      const T d1 = std::sqrt(squared_norm(anchor - p_anchor));
      // The list in one walk, warm-started from the closest triangle, from a random one (a
      // radius that shrinks as the walk goes), or from none (triangle 0: a walk over most of the
      // sheet, the list filled and dropping entries).
      const std::int32_t n_triangles = std::int32_t(sheet.triangles.size());
      std::int32_t t_list = trial % 5 == 0   ? -1
                            : trial % 5 == 1 ? std::int32_t(unit(rng) * n_triangles) % n_triangles
                                             : t_anchor;
      const std::int32_t count =
          list_surface_candidates<kCapacity>(view, anchor, skin, t_list, list, distance, 1);
      // Against every triangle: the list holds each one within d1 + 2 s (up to round-off at the
      // rim), with its distance, and none beyond; a list of capacity 4 either holds the same
      // first entries or reports an overflow when more than 4 lie within d1 + 2 s.
      if (trial % 3 == 0) {
        const T radius = d1 + T(2) * skin;
        std::vector<std::pair<T, std::int32_t>> within;
        bool rim = false;  // a triangle within round-off of the rim
        for (std::int32_t t = 0; t < n_triangles; ++t) {
          const Vec3<T>* c = &corners[3 * std::size_t(t)];
          const T d = std::sqrt(
              squared_norm(anchor - physics::closest_point_on_triangle(anchor, c[0], c[1], c[2])));
          if (d <= radius) within.push_back({d, t});
          rim = rim || std::abs(d - radius) <= T(1e-5) * radius;
        }
        std::sort(within.begin(), within.end());
        if (count >= 0 && !rim) {
          ASSERT_EQ(std::size_t(count), within.size()) << name << ", trial " << trial;
          for (std::int32_t n = 0; n < count; ++n) {
            ASSERT_EQ(list[n], within[std::size_t(n)].second) << name << ", trial " << trial;
            ASSERT_EQ(distance[n], within[std::size_t(n)].first) << name << ", trial " << trial;
          }
        }
        std::int32_t small_list[4];
        T small_distance[4];
        std::int32_t t_small = t_list;
        const std::int32_t small =
            list_surface_candidates<4>(view, anchor, skin, t_small, small_list, small_distance, 1);
        if (!rim) {
          const bool overflowed = small < 0;
          const bool over_four = within.size() > 4;
          ASSERT_EQ(overflowed, over_four) << name << ", trial " << trial;
          for (std::int32_t n = 0; n < small; ++n)
            ASSERT_EQ(small_list[n], within[std::size_t(n)].second) << name << ", trial " << trial;
        }
        ++brute_checked;
        small_overflows += small < 0 ? 1 : 0;
      }
      if (count < 0) continue;  // overflow: such a node searches the grid instead
      ASSERT_GT(count, 0) << name;
      // The walk's closest triangle: at the search's distance (the same bits).
      ASSERT_EQ(distance[0], d1) << name << ", trial " << trial;
      for (std::int32_t n = 1; n < count; ++n) ASSERT_LE(distance[n - 1], distance[n]) << name;
      // The node: within 0.999 s of the anchor (none moved in a quarter of the trials: ties stay
      // exact ties), its warm start the anchor's closest triangle or any listed one.
      Vec3<T> x = anchor;
      if (trial % 4 != 0) {
        Vec3<T> dir{T(unit(rng) - 0.5), T(unit(rng) - 0.5), T(unit(rng) - 0.5)};
        const T len = std::sqrt(squared_norm(dir));
        if (len > T(0)) x = anchor + (T(0.999) * skin * T(unit(rng)) / len) * dir;
      }
      const std::int32_t warm =
          trial % 2 == 0 ? t_anchor : list[std::int32_t(unit(rng) * double(count)) % count];
      std::int32_t t_full = warm, t_listed = warm;
      const Vec3<T> p_full = closest_surface_search<T, true>(view, x, t_full);
      const T moved = std::sqrt(squared_norm(x - anchor));
      const T margin = skin * T(0.0625);
      const Vec3<T> warm_corners[3] = {corners[3 * std::size_t(warm)],
                                       corners[3 * std::size_t(warm) + 1],
                                       corners[3 * std::size_t(warm) + 2]};
      const Vec3<T> p_listed = closest_listed_point(corners.data(), warm_corners, list, distance, 1,
                                                    count, x, moved, margin, t_listed);
      ASSERT_EQ(t_full, t_listed) << name << ": skin " << skin_cells << " cells, trial " << trial;
      for (int k = 0; k < 3; ++k) ASSERT_EQ(p_full[k], p_listed[k]) << name << ", trial " << trial;
      // How much the cull skipped: entries other than the warm start beyond its bound.
      const T bound = std::sqrt(squared_norm(x - p_full)) + moved + margin;
      ++queries;
      for (std::int32_t n = 0; n < count; ++n) {
        if (list[n] == warm) continue;
        ++entries;
        if (distance[n] > bound) ++culled;
      }
      if (t_full != warm) continue;
      for (std::int32_t n = 0; n < count; ++n)
        if (list[n] != warm && squared_norm(x - physics::closest_point_on_triangle(
                                                    x, corners[3 * std::size_t(list[n])],
                                                    corners[3 * std::size_t(list[n]) + 1],
                                                    corners[3 * std::size_t(list[n]) + 2])) ==
                                   squared_norm(x - p_full))
          ++ties;
    }
  }
  std::printf(
      "[ measured ] %s: %ld queries, %.2f listed entries besides the warm start per query, "
      "%.0f%% of them culled; %ld queries with an exact tie kept by the warm start\n",
      name, queries, double(entries) / double(queries), 100.0 * double(culled) / double(entries),
      ties);
  std::printf(
      "[ measured ] %s: %ld lists checked against every triangle, %ld of them over 4 "
      "entries\n",
      name, brute_checked, small_overflows);
  EXPECT_GT(culled, entries / 4) << name << ": the cull must skip entries";
  EXPECT_GT(small_overflows, brute_checked / 10) << name << ": lists of 4 must overflow";
  EXPECT_LT(small_overflows, brute_checked) << name << ": lists of 4 must not always overflow";
  EXPECT_GT(ties, 100) << name << ": the trials must contain exact ties";
}

TEST(SlidingGrid, ListedQueryGivesTheFullSearchsTriangleAndPointInFloat) {
  expect_listed_query_is_exact<float>("float");
}

TEST(SlidingGrid, ListedQueryGivesTheFullSearchsTriangleAndPointInDouble) {
  expect_listed_query_is_exact<double>("double");
}

}  // namespace
}  // namespace sinew::simulator
