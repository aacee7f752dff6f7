#include "sinew/postprocess/model_preview.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "sinew/common/error.hpp"
#include "sinew/formats/file_kind.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/model_file.hpp"

namespace sinew::postprocess {
namespace {

namespace h5 = formats::hdf5;
using formats::Lattice;

// The outward faces of a set of voxels as triangles (two per face), corners at lattice points.
PreviewMesh voxel_boundary(const formats::Model& m, const std::vector<Lattice>& voxels,
                           const std::string& name) {
  PreviewMesh out;
  out.name = name;
  std::vector<Lattice> sorted = voxels;
  std::sort(sorted.begin(), sorted.end(), formats::lattice_less);
  auto present = [&](const Lattice& l) {
    return std::binary_search(sorted.begin(), sorted.end(), l, formats::lattice_less);
  };
  std::map<Lattice, std::int32_t> vertex;
  auto corner = [&](const Lattice& l) {
    const auto [it, fresh] = vertex.emplace(l, std::int32_t(out.positions.size() / 3));
    if (fresh)
      for (int k = 0; k < 3; ++k)
        out.positions.push_back(
            float(m.grid.origin[std::size_t(k)] + m.grid.voxel_size * l[std::size_t(k)]));
    return it->second;
  };
  for (const auto& v : sorted) {
    for (int axis = 0; axis < 3; ++axis) {
      for (int side = 0; side < 2; ++side) {
        Lattice n = v;
        n[std::size_t(axis)] += side ? 1 : -1;
        if (present(n)) continue;
        // The face's four corners: the axis fixed at v + side, the other two running 0..1.
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        std::array<std::int32_t, 4> q{};
        const int da[4] = {0, 1, 1, 0}, db[4] = {0, 0, 1, 1};
        for (int c = 0; c < 4; ++c) {
          Lattice p = v;
          p[std::size_t(axis)] += side;
          p[std::size_t(a)] += da[c];
          p[std::size_t(b)] += db[c];
          q[std::size_t(c)] = corner(p);
        }
        out.triangles.insert(out.triangles.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
      }
    }
  }
  return out;
}

PreviewMesh surface_mesh(const formats::Surface& s) {
  PreviewMesh out;
  out.name = s.name;
  for (const auto& v : s.vertices)
    for (double x : v) out.positions.push_back(float(x));
  for (const auto& t : s.triangles)
    for (auto i : t) out.triangles.push_back(i);
  return out;
}

// One muscle's streamlines through its element-wise fibre field.
void trace_muscle(const formats::Model& m, std::size_t mi, int spacing,
                  std::vector<Streamline>& out) {
  const auto& mu = m.muscles[mi];
  std::map<Lattice, std::size_t> at;  // lattice -> entry of mu
  for (std::size_t k = 0; k < mu.elements.size(); ++k)
    at.emplace(m.element_lattice[std::size_t(mu.elements[k])], k);
  const double h = m.grid.voxel_size;
  auto lattice_of = [&](const Point& p) {
    Lattice l{};
    for (int k = 0; k < 3; ++k)
      l[std::size_t(k)] =
          std::int32_t(std::floor((p[std::size_t(k)] - m.grid.origin[std::size_t(k)]) / h));
    return l;
  };
  // The fibre at p, turned to agree with `along`; false outside the muscle.
  auto fibre = [&](const Point& p, const Point& along, Point& f) {
    const auto it = at.find(lattice_of(p));
    if (it == at.end()) return false;
    f = mu.fibres[it->second];
    if (f[0] * along[0] + f[1] * along[1] + f[2] * along[2] < 0)
      for (double& x : f) x = -x;
    return true;
  };
  const int max_steps =
      4 * std::max({m.grid.dims[0], m.grid.dims[1], m.grid.dims[2]}) * 2;  // h/2 steps
  for (const auto& [l, k] : at) {
    if (l[0] % spacing || l[1] % spacing || l[2] % spacing) continue;
    const Point seed{m.grid.origin[0] + h * (l[0] + 0.5), m.grid.origin[1] + h * (l[1] + 0.5),
                     m.grid.origin[2] + h * (l[2] + 0.5)};
    std::vector<Point> half[2];
    for (int dir = 0; dir < 2; ++dir) {
      Point along = mu.fibres[k];
      if (dir)
        for (double& x : along) x = -x;
      Point p = seed;
      for (int step = 0; step < max_steps; ++step) {
        Point f1, f2;
        if (!fibre(p, along, f1)) break;
        Point mid;
        for (int c = 0; c < 3; ++c)
          mid[std::size_t(c)] = p[std::size_t(c)] + h / 4 * f1[std::size_t(c)];
        if (!fibre(mid, f1, f2)) break;
        Point next;
        for (int c = 0; c < 3; ++c)
          next[std::size_t(c)] = p[std::size_t(c)] + h / 2 * f2[std::size_t(c)];
        if (at.find(lattice_of(next)) == at.end()) break;
        half[dir].push_back(next);
        along = f2;
        p = next;
      }
    }
    Streamline s;
    s.muscle = mi;
    s.points.assign(half[1].rbegin(), half[1].rend());
    s.points.push_back(seed);
    s.points.insert(s.points.end(), half[0].begin(), half[0].end());
    if (s.points.size() >= 2) out.push_back(std::move(s));
  }
}

void draw_line(Image& img, double x0, double y0, double x1, double y1, Rgb c, int thickness) {
  const double len = std::max(std::abs(x1 - x0), std::abs(y1 - y0));
  const int n = std::max(1, int(std::ceil(len)));
  for (int i = 0; i <= n; ++i) {
    const double t = double(i) / n;
    const int x = int(std::floor(x0 + t * (x1 - x0))), y = int(std::floor(y0 + t * (y1 - y0)));
    for (int dy = 0; dy < thickness; ++dy)
      for (int dx = 0; dx < thickness; ++dx) img.set(x + dx, y + dy, c);
  }
}

}  // namespace

bool is_model_file(const std::string& path) {
  try {
    if (!std::filesystem::exists(path) || !h5::is_hdf5(path)) return false;
    auto file = h5::open_file(path, false);
    return formats::has_format(file, path, formats::kModelFormatName);
  } catch (const std::exception&) {
    return false;
  }
}

ModelPreview make_model_preview(const formats::Model& m, const std::string& skin, int spacing,
                                double min_fraction) {
  if (spacing < 1) throw ConfigError("", "--seed-spacing", "must be at least 1");
  if (!(min_fraction > 0 && min_fraction <= 1))
    throw ConfigError("", "min_fraction", "must be in (0, 1]");
  ModelPreview p;
  std::string known;
  for (const auto& s : m.surfaces) {
    if (s.role != formats::SurfaceRole::visual) continue;
    known += (known.empty() ? "" : ", ") + s.name;
    if (p.skin.name.empty() && (skin.empty() || s.name == skin)) p.skin = surface_mesh(s);
  }
  if (p.skin.name.empty()) {
    if (!skin.empty())
      throw ConfigError("", "--surface",
                        fmt::format("the model has no visual surface '{}' (it has: {})", skin,
                                    known.empty() ? "none" : known));
    p.skin = voxel_boundary(m, m.element_lattice, "elements");
  }
  for (std::size_t i = 0; i < m.muscles.size(); ++i) {
    const auto& mu = m.muscles[i];
    std::vector<Lattice> voxels;
    for (std::size_t k = 0; k < mu.elements.size(); ++k)
      if (mu.fractions[k] >= min_fraction)
        voxels.push_back(m.element_lattice[std::size_t(mu.elements[k])]);
    p.muscles.push_back(voxel_boundary(m, voxels, mu.name));
    trace_muscle(m, i, spacing, p.streamlines);
  }
  return p;
}

Image render_model_preview(const ModelPreview& p, const PreviewSettings& s) {
  if (!(s.skin_opacity >= 0 && s.skin_opacity <= 1))
    throw ConfigError("", "--skin-opacity", "must be in [0, 1]");
  std::vector<float> all = p.skin.positions;
  PreviewMesh inner;
  for (const auto& mm : p.muscles) {
    const auto base = std::int32_t(inner.positions.size() / 3);
    inner.positions.insert(inner.positions.end(), mm.positions.begin(), mm.positions.end());
    for (auto t : mm.triangles) inner.triangles.push_back(base + t);
  }
  all.insert(all.end(), inner.positions.begin(), inner.positions.end());
  RenderOptions o;
  o.width = s.width;
  o.height = s.height;
  o.camera =
      aim_camera(frame_view(all, s.view, double(s.width) / s.height, s.up), s.target, s.zoom);
  Image below(s.width, s.height, o.shading.background);
  if (!inner.triangles.empty()) {
    RenderOptions mo = o;
    mo.shading.base = kMuscleColor;
    below = render(inner.positions, inner.triangles, mo);
  }
  if (s.fibres) {
    const int thickness = std::max(1, s.width / 600);
    for (const auto& line : p.streamlines) {
      for (std::size_t k = 0; k + 1 < line.points.size(); ++k) {
        double x0, y0, x1, y1;
        if (project_point(o.camera, s.width, s.height, line.points[k], x0, y0) &&
            project_point(o.camera, s.width, s.height, line.points[k + 1], x1, y1))
          draw_line(below, x0, y0, x1, y1, kFibreColor, thickness);
      }
    }
  }
  Image out = below;
  if (!p.skin.triangles.empty() && s.skin_opacity > 0) {
    const Image skin = render(p.skin.positions, p.skin.triangles, o);
    const double a = s.skin_opacity;
    for (int y = 0; y < s.height; ++y) {
      for (int x = 0; x < s.width; ++x) {
        const Rgb c = skin.at(x, y);
        if (c == o.shading.background) continue;
        const Rgb b = below.at(x, y);
        auto mix = [a](std::uint8_t f, std::uint8_t g) {
          return std::uint8_t(std::lround(a * f + (1 - a) * g));
        };
        out.set(x, y, {mix(c.r, b.r), mix(c.g, b.g), mix(c.b, b.b)});
      }
    }
  }
  if (!s.crop) return out;
  const auto& c = *s.crop;
  return crop(out, c[0], c[1], c[2], c[3]);
}

}  // namespace sinew::postprocess
