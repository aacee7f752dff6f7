#pragma once
// A sliding surface for the benchmarks' block models: a height field z = height(x, y) under the
// block, and the bindings of the block's bottom nodes to it. Shared by simulator_cpu_bench and
// accuracy_study.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <utility>

#include "sinew/common/math.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/simulator/physics/sliding.hpp"

namespace sinew::bench {

// A sliding surface sampled on cells_x × cells_y square cells of side `spacing` whose first corner
// is (x0, y0): vertices row by row ((cells_x + 1) per row, x fastest), two triangles per cell,
// (a, b, c) and (a, c, d) from its corners a = (i, j), b = (i + 1, j), c = (i + 1, j + 1),
// d = (i, j + 1): counter-clockwise seen from +z.
struct HeightField {
  formats::Surface surface;
  double x0 = 0, y0 = 0, spacing = 0;
  int cells_x = 0, cells_y = 0;
};

template <typename Height>
HeightField make_height_field(std::string name, double x0, double y0, double spacing, int cells_x,
                              int cells_y, Height height) {
  HeightField f{{}, x0, y0, spacing, cells_x, cells_y};
  f.surface.name = std::move(name);
  f.surface.role = formats::SurfaceRole::sliding;
  for (int j = 0; j <= cells_y; ++j)
    for (int i = 0; i <= cells_x; ++i) {
      const double x = x0 + spacing * i, y = y0 + spacing * j;
      f.surface.vertices.push_back({x, y, height(x, y)});
    }
  for (int j = 0; j < cells_y; ++j)
    for (int i = 0; i < cells_x; ++i) {
      const formats::Index a = j * (cells_x + 1) + i, b = a + 1, c = a + cells_x + 2,
                           d = a + cells_x + 1;
      f.surface.triangles.push_back({a, b, c});
      f.surface.triangles.push_back({a, c, d});
    }
  return f;
}

// Appends f's surface to the model and binds every bottom node (lattice k = 0) to it at its
// current distance: the closest triangle among the cells within `radius` cells (along x and y) of
// the cell below the node, the first one met when several are as close (a gentle height field
// has its closest triangle within a few cells).
inline void bind_bottom_to_height_field(formats::Model& model, const HeightField& f, int radius) {
  using V = Vec3<double>;
  const auto surface = static_cast<formats::Index>(model.surfaces.size());
  model.surfaces.push_back(f.surface);
  const auto& s = model.surfaces.back();
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    if (model.node_lattice[n][2] != 0) continue;
    const auto x = model.node_position(formats::Index(n));
    const V p{x[0], x[1], x[2]};
    const int ci = int(std::floor((x[0] - f.x0) / f.spacing)),
              cj = int(std::floor((x[1] - f.y0) / f.spacing));
    double best = 1e300;
    formats::Index bt = 0;
    for (int j = std::max(0, cj - radius); j <= std::min(f.cells_y - 1, cj + radius); ++j)
      for (int i = std::max(0, ci - radius); i <= std::min(f.cells_x - 1, ci + radius); ++i)
        for (int t = 0; t < 2; ++t) {
          const int id = 2 * (j * f.cells_x + i) + t;
          const auto& tri = s.triangles[std::size_t(id)];
          const auto& a = s.vertices[std::size_t(tri[0])];
          const auto& b = s.vertices[std::size_t(tri[1])];
          const auto& c = s.vertices[std::size_t(tri[2])];
          const double d =
              norm(p - simulator::physics::closest_point_on_triangle(
                           p, V{a[0], a[1], a[2]}, V{b[0], b[1], b[2]}, V{c[0], c[1], c[2]}));
          if (d < best) {
            best = d;
            bt = id;
          }
        }
    model.sliding.push_back({formats::Index(n), surface, best, bt});
  }
}

}  // namespace sinew::bench
