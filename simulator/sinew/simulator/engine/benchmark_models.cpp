#include "sinew/simulator/engine/benchmark_models.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <set>
#include <tuple>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/formats/box_model.hpp"
#include "sinew/simulator/passes/sliding_grid.hpp"

namespace sinew::simulator {
using formats::Index;
namespace {

formats::Material tissue(const char* name, double e, double nu = 0.49, double rho = 11000) {
  return formats::make_neo_hookean_material(name, e, nu, rho);
}

}  // namespace

formats::Model make_skin_block_model(int nx, int ny, int nz, double h) {
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  const double top = nz * h;
  spec.materials = {tissue("hypodermis", 34e3), tissue("dermis", 81.4e3),
                    tissue("stratum_corneum", 48e6)};
  spec.layer_boundaries = {top - 1.82e-3 > 0 ? top - 1.82e-3 : top * 0.2, top - 0.02e-3};
  spec.created = "2026-01-01T00:00:00Z";
  return formats::make_box_model(spec);
}

formats::Model make_forehead_model(int nx, int ny, int nz, double h) {
  formats::BoxSpec spec;
  spec.dims = {nx, ny, nz};
  spec.voxel_size = h;
  const double top = nz * h;
  spec.materials = {tissue("muscle", 0.5e6), tissue("hypodermis", 34e3), tissue("dermis", 81.4e3),
                    tissue("stratum_corneum", 48e6)};
  spec.layer_boundaries = {top / 4, top / 2, top - top * 0.01};
  const int gap = std::max(1, nx / 14);
  for (int m = 0; m < 2; ++m) {
    formats::BoxMuscleSpec ms;
    ms.name = m == 0 ? "frontalis_left" : "frontalis_right";
    ms.material = 0;
    const int x0 = m == 0 ? gap : nx / 2 + gap / 2;
    const int x1 = m == 0 ? nx / 2 - gap / 2 : nx - gap;
    ms.element_min = {x0, 0, 0};
    ms.element_max = {x1, std::max(1, ny * 5 / 6), 1};
    ms.fibre = {0, 1, 0};
    spec.muscles.push_back(ms);
  }
  spec.created = "2026-01-01T00:00:00Z";
  formats::Model model = formats::make_box_model(spec);

  // Skull: z = −0.25 h − (x − xc)² / (2R), sampled every 2 h, triangles facing +z; R such that the
  // surface falls 2 h below its middle at the slab's sides.
  const double xc = 0.5 * nx * h, radius = xc * xc / (4 * h);
  const int sx = nx / 2 + 2, sy = ny / 2 + 2;
  formats::Surface skull;
  skull.name = "skull";
  skull.role = formats::SurfaceRole::sliding;
  for (int j = 0; j <= sy; ++j)
    for (int i = 0; i <= sx; ++i) {
      const double x = -h + 2 * h * i, y = -h + 2 * h * j;
      skull.vertices.push_back({x, y, -0.25 * h - (x - xc) * (x - xc) / (2 * radius)});
    }
  auto vid = [&](int i, int j) { return Index(j * (sx + 1) + i); };
  for (int j = 0; j < sy; ++j)
    for (int i = 0; i < sx; ++i) {
      skull.triangles.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      skull.triangles.push_back({vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
    }
  std::vector<Vec3<double>> v;
  for (const auto& p : skull.vertices) v.push_back({p[0], p[1], p[2]});
  std::vector<Vec3<double>> normals;
  std::vector<std::array<std::int32_t, 3>> tris(skull.triangles.begin(), skull.triangles.end());
  for (const auto& t : tris)
    normals.push_back(
        physics::triangle_normal(v[std::size_t(t[0])], v[std::size_t(t[1])], v[std::size_t(t[2])]));
  const SurfaceGrid grid = build_surface_grid(skull.vertices, tris);
  const SurfaceLists<double> lists = make_surface_lists(grid, v, tris);
  SurfaceView<double> view{v.data(),
                           tris.data(),
                           normals.data(),
                           std::int32_t(tris.size()),
                           grid.cell_offsets.data(),
                           grid.cell_triangles.data(),
                           lists.corners.data(),
                           lists.cell.data(),
                           {},
                           0,
                           {}};
  for (int k = 0; k < 3; ++k) {
    view.origin[k] = grid.origin[std::size_t(k)];
    view.dims[k] = grid.dims[std::size_t(k)];
  }
  view.cell = grid.cell;
  model.surfaces.push_back(skull);
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    const auto& l = model.node_lattice[n];
    if (l[2] != 0) continue;
    const auto p = model.node_position(Index(n));
    const int ci = std::min(sx - 1, (l[0] + 1) / 2), cj = std::min(sy - 1, (l[1] + 1) / 2);
    std::int32_t tri = 2 * (cj * sx + ci);
    const Vec3<double> x{p[0], p[1], p[2]};
    const Vec3<double> c = closest_surface_point(view, x, tri);
    formats::SlidingBinding b;
    b.node = Index(n);
    b.surface = 0;
    b.rest_distance = norm(x - c);
    b.rest_triangle = tri;
    model.sliding.push_back(b);
  }
  return model;
}

namespace {

struct Ellipsoid {
  std::array<double, 3> c, r;
};

// The body of make_soft_body_model: cells (voxel side h) whose centres lie in any of the
// ellipsoids (reference units, times s), and, when floor is finite, above the plane z = floor · s;
// with largest_only, only the largest face-connected piece is kept.
formats::Model soft_body_from_parts(std::vector<Ellipsoid> parts, double s, double h, double floor,
                                    bool largest_only, const char* tool) {
  for (auto& p : parts)
    for (int k = 0; k < 3; ++k) {
      p.c[std::size_t(k)] *= s;
      p.r[std::size_t(k)] *= s;
    }
  std::set<std::tuple<int, int, int>> cells;  // (k, j, i): the model's sort order
  for (const auto& p : parts) {
    for (int i = int(p.c[0] - p.r[0]) - 1; i < int(p.c[0] + p.r[0]) + 2; ++i)
      for (int j = int(p.c[1] - p.r[1]) - 1; j < int(p.c[1] + p.r[1]) + 2; ++j)
        for (int k = int(p.c[2] - p.r[2]) - 1; k < int(p.c[2] + p.r[2]) + 2; ++k) {
          const double a = (i + 0.5 - p.c[0]) / p.r[0], b = (j + 0.5 - p.c[1]) / p.r[1],
                       c = (k + 0.5 - p.c[2]) / p.r[2];
          if (a * a + b * b + c * c <= 1 && k + 0.5 >= floor * s) cells.insert({k, j, i});
        }
  }
  if (largest_only && !cells.empty()) {
    std::set<std::tuple<int, int, int>> best, seen;
    for (const auto& start : cells) {
      if (seen.count(start)) continue;
      std::set<std::tuple<int, int, int>> piece{start};
      std::vector<std::tuple<int, int, int>> stack{start};
      seen.insert(start);
      while (!stack.empty()) {
        const auto [k, j, i] = stack.back();
        stack.pop_back();
        const std::tuple<int, int, int> next[6] = {{k - 1, j, i}, {k + 1, j, i}, {k, j - 1, i},
                                                   {k, j + 1, i}, {k, j, i - 1}, {k, j, i + 1}};
        for (const auto& n : next)
          if (cells.count(n) && seen.insert(n).second) {
            piece.insert(n);
            stack.push_back(n);
          }
      }
      if (piece.size() > best.size()) best = std::move(piece);
    }
    cells = std::move(best);
  }
  int lo[3] = {1 << 30, 1 << 30, 1 << 30}, hi[3] = {-(1 << 30), -(1 << 30), -(1 << 30)};
  for (const auto& [k, j, i] : cells) {
    const int v[3] = {i, j, k};
    for (int d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], v[d]);
      hi[d] = std::max(hi[d], v[d]);
    }
  }
  formats::Model m;
  m.grid.voxel_size = h;
  for (int d = 0; d < 3; ++d) {
    m.grid.origin[std::size_t(d)] = lo[d] * h;
    m.grid.dims[std::size_t(d)] = hi[d] - lo[d] + 1;
  }
  for (const auto& [k, j, i] : cells)
    m.element_lattice.push_back({i - lo[0], j - lo[1], k - lo[2]});
  formats::build_lattice_topology(m);
  m.materials = {formats::make_neo_hookean_material("core", 400e3, 0.45, 1000),
                 formats::make_neo_hookean_material("flesh", 200e3, 0.45, 1000),
                 formats::make_neo_hookean_material("skin", 100e3, 0.45, 1000)};
  m.material_offsets.push_back(0);
  const double body_r = 19 * s;
  for (const auto& l : m.element_lattice) {
    const double x = (l[0] + lo[0] + 0.5), y = (l[1] + lo[1] + 0.5), z = (l[2] + lo[2] + 0.5);
    const double r = std::sqrt(x * x + y * y + z * z) / body_r;
    m.material_ids.push_back(r < 0.4 ? 0 : (r < 0.75 ? 1 : 2));
    m.material_fractions.push_back(1.0);
    m.material_offsets.push_back(formats::Offset(m.material_ids.size()));
  }
  formats::NamedSet feet{"feet", {}};
  for (std::size_t n = 0; n < m.node_count(); ++n)
    if (m.node_lattice[n][2] == 0) feet.ids.push_back(Index(n));
  m.node_sets.push_back(feet);
  m.provenance.tool = tool;
  m.provenance.created = "2026-01-01T00:00:00Z";
  return m;
}

}  // namespace

formats::Model make_soft_body_model(double s, double h) {
  std::vector<Ellipsoid> parts = {{{0, 0, 0}, {19, 11, 9}},      {{8, -13, 2}, {10, 2.4, 2.4}},
                                  {{8, 13, 2}, {10, 2.4, 2.4}},  {{24, 0, 6}, {7, 7, 7}},
                                  {{-30, 0, 0}, {14, 2.5, 2.5}}, {{26, -4, 15}, {2, 2, 6}},
                                  {{26, 4, 15}, {2, 2, 6}}};
  for (int sxn : {-1, 1})
    for (int syn : {-1, 1}) parts.push_back({{12.0 * sxn, 8.0 * syn, -17}, {2.6, 2.6, 13}});
  return soft_body_from_parts(std::move(parts), s, h, -HUGE_VAL, false,
                              "sinew::simulator::make_soft_body_model");
}

// ---- Sample models -------------------------------------------------------------------------------

void add_boundary_visual_surface(formats::Model& model, const std::string& name,
                                 const std::string& skip_set) {
  for (const auto& surface : model.surfaces)
    if (surface.name == name)
      throw ConfigError("", "surface", "the model already has a surface named '" + name + "'");
  std::vector<char> skip(model.node_count(), 0);
  if (!skip_set.empty()) {
    const formats::NamedSet* set = nullptr;
    for (const auto& s : model.node_sets)
      if (s.name == skip_set) set = &s;
    if (set == nullptr)
      throw ConfigError("", "skip_set", "the model has no node set '" + skip_set + "'");
    for (const Index n : set->ids) skip[std::size_t(n)] = 1;
  }
  const auto& dims = model.grid.dims;
  const std::size_t nx = std::size_t(dims[0]), ny = std::size_t(dims[1]), nz = std::size_t(dims[2]);
  std::vector<Index> element_at(nx * ny * nz, -1);
  auto cell = [&](const formats::Lattice& l) {
    return std::size_t(l[0]) + nx * (std::size_t(l[1]) + ny * std::size_t(l[2]));
  };
  for (std::size_t e = 0; e < model.element_count(); ++e)
    element_at[cell(model.element_lattice[e])] = Index(e);

  // Faces as hex8 corners, counter-clockwise seen from outside (VTK order), with their neighbour.
  struct Face {
    int axis, side;
    std::array<int, 4> corners;
  };
  constexpr std::array<Face, 6> kFaces = {{{0, -1, {0, 4, 7, 3}},
                                           {0, +1, {1, 2, 6, 5}},
                                           {1, -1, {0, 1, 5, 4}},
                                           {1, +1, {3, 7, 6, 2}},
                                           {2, -1, {0, 3, 2, 1}},
                                           {2, +1, {4, 5, 6, 7}}}};
  formats::Surface surface;
  surface.name = name;
  surface.role = formats::SurfaceRole::visual;
  std::vector<Index> vertex_of(model.node_count(), -1);
  for (std::size_t e = 0; e < model.element_count(); ++e) {
    const auto& base = model.element_lattice[e];
    for (const Face& face : kFaces) {
      formats::Lattice n = base;
      n[std::size_t(face.axis)] += face.side;
      const int dim = dims[std::size_t(face.axis)];
      const int c = n[std::size_t(face.axis)];
      if (c >= 0 && c < dim && element_at[cell(n)] >= 0) continue;  // interior face
      std::array<Index, 4> v{};
      int skipped = 0;
      for (int a = 0; a < 4; ++a) {
        const int corner = face.corners[std::size_t(a)];
        const Index node = model.element_nodes[e][std::size_t(corner)];
        skipped += skip[std::size_t(node)];
        v[std::size_t(a)] = node;
      }
      if (skipped == 4) continue;
      for (int a = 0; a < 4; ++a) {
        const int corner = face.corners[std::size_t(a)];
        const Index node = v[std::size_t(a)];
        Index& id = vertex_of[std::size_t(node)];
        if (id < 0) {
          id = Index(surface.vertices.size());
          surface.vertices.push_back(model.node_position(node));
          surface.embedding_element.push_back(Index(e));
          const auto& k = formats::kHexCorner[std::size_t(corner)];
          surface.embedding_local.push_back({2.0 * k[0] - 1.0, 2.0 * k[1] - 1.0, 2.0 * k[2] - 1.0});
        }
        v[std::size_t(a)] = id;
      }
      surface.triangles.push_back({v[0], v[1], v[2]});
      surface.triangles.push_back({v[0], v[2], v[3]});
    }
  }
  model.surfaces.push_back(std::move(surface));
}

formats::Model make_skin_block_sample_model(int nx, int ny, int nz, double h, int press_width) {
  formats::Model model = make_skin_block_model(nx, ny, nz, h);
  add_boundary_visual_surface(model, "skin", "z_min");
  const int w = press_width > 0 ? press_width : std::max(1, int(std::lround(nx / 10.0)));
  // Twice the lattice coordinate, so odd and even sizes centre alike: |2i − nx| ≤ w.
  formats::NamedSet press{"press", {}};
  for (std::size_t n = 0; n < model.node_count(); ++n) {
    const auto& l = model.node_lattice[n];
    if (l[2] == nz && std::abs(2 * l[0] - nx) <= w && std::abs(2 * l[1] - ny) <= w)
      press.ids.push_back(Index(n));
  }
  model.node_sets.push_back(std::move(press));
  return model;
}

formats::Model make_soft_body_sample_model(double scale, double h) {
  // make_soft_body_model's legs end below the body's belly (they meet it along edges only: a
  // mechanism under gravity), so here they reach up into it, stand further in, and end on flat
  // pads cut by the floor z = −28; the arms move 1 in so they overlap the body along their length.
  std::vector<Ellipsoid> parts = {{{0, 0, 0}, {19, 11, 9}},      {{8, -12, 2}, {10, 2.4, 2.4}},
                                  {{8, 12, 2}, {10, 2.4, 2.4}},  {{24, 0, 6}, {7, 7, 7}},
                                  {{-30, 0, 0}, {14, 2.5, 2.5}}, {{26, -4, 15}, {2, 2, 6}},
                                  {{26, 4, 15}, {2, 2, 6}}};
  for (int sxn : {-1, 1})
    for (int syn : {-1, 1}) {
      parts.push_back({{10.0 * sxn, 6.0 * syn, -12}, {3.2, 3.2, 17}});
      parts.push_back({{10.0 * sxn + 1.5, 6.0 * syn, -28}, {4.5, 3.2, 3}});
    }
  formats::Model model = soft_body_from_parts(std::move(parts), scale, h, -28, true,
                                              "sinew::simulator::make_soft_body_sample_model");
  add_boundary_visual_surface(model, "skin");
  return model;
}

double model_mass(const formats::Model& model) {
  const double volume = model.grid.voxel_size * model.grid.voxel_size * model.grid.voxel_size;
  double mass = 0;
  for (std::size_t e = 0; e < model.element_count(); ++e)
    for (auto k = model.material_offsets[e]; k < model.material_offsets[e + 1]; ++k)
      mass += model.material_fractions[std::size_t(k)] *
              model.materials[std::size_t(model.material_ids[std::size_t(k)])].density * volume;
  return mass;
}

}  // namespace sinew::simulator
