#include "sinew/voxelizer/rig.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/voxelizer/distance.hpp"
#include "sinew/voxelizer/mesh_source.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {
namespace {

constexpr double kSpacing = 1.5e-3;  // m, target edge length of the muscles' grids

Vec3d unit(const Vec3d& v) {
  return (1.0 / norm(v)) * v;
}

// Closest skin point and the skin's normal there: the area-weighted vertex normals interpolated
// over the closest triangle (smooth across the triangles' edges, unlike the faces' normals).
class SkinProjector {
 public:
  explicit SkinProjector(const TriangleMesh& skin) : skin_(skin), query_(skin), winding_(skin) {
    normals_.assign(skin.vertices.size(), Vec3d{0, 0, 0});
    for (const auto& t : skin.triangles) {
      const Vec3d& a = skin.vertices[static_cast<std::size_t>(t[0])];
      const Vec3d n = cross(skin.vertices[static_cast<std::size_t>(t[1])] - a,
                            skin.vertices[static_cast<std::size_t>(t[2])] - a);
      for (auto v : t) normals_[static_cast<std::size_t>(v)] += n;
    }
    for (auto& n : normals_)
      if (norm(n) > 0) n = unit(n);
  }
  struct Hit {
    Vec3d point, normal;
  };
  Hit project(const Vec3d& p) const {
    const auto h = query_.closest(p);
    const auto& t = skin_.triangles[static_cast<std::size_t>(h.triangle)];
    const Vec3d& a = skin_.vertices[static_cast<std::size_t>(t[0])];
    const Vec3d& b = skin_.vertices[static_cast<std::size_t>(t[1])];
    const Vec3d& c = skin_.vertices[static_cast<std::size_t>(t[2])];
    // Barycentric coordinates of the closest point (it lies in the triangle).
    const Vec3d n = cross(b - a, c - a);
    const double area2 = dot(n, n);
    double wa = 1.0 / 3, wb = 1.0 / 3, wc = 1.0 / 3;
    if (area2 > 0) {
      wb = dot(cross(h.point - a, c - a), n) / area2;
      wc = dot(cross(b - a, h.point - a), n) / area2;
      wa = 1 - wb - wc;
    }
    Vec3d nn = wa * normals_[static_cast<std::size_t>(t[0])] +
               wb * normals_[static_cast<std::size_t>(t[1])] +
               wc * normals_[static_cast<std::size_t>(t[2])];
    if (!(norm(nn) > 0)) nn = area2 > 0 ? unit(n) : Vec3d{0, 0, 1};
    return {h.point, unit(nn)};
  }
  double distance(const Vec3d& p) const { return query_.distance(p); }
  // Where the line p + t·dir (dir unit) crosses the skin, |t| ≤ reach: bisection on inside/outside
  // (the winding number), 26 halvings (reach · 2^−25). Unlike the closest point it does not jump
  // between two folds of the skin equidistant from p (the lips at the mouth's crease). Falls back
  // to the closest point when the line does not cross the skin there.
  Hit project_along(const Vec3d& p, const Vec3d& dir, double reach) const {
    Vec3d out = p + reach * dir, in = p - reach * dir;
    if (winding_.inside(out) || !winding_.inside(in)) return project(p);
    for (int k = 0; k < 26; ++k) {
      const Vec3d mid = 0.5 * (out + in);
      (winding_.inside(mid) ? in : out) = mid;
    }
    return project(0.5 * (out + in));
  }

 private:
  const TriangleMesh& skin_;
  DistanceQuery query_;
  WindingNumber winding_;
  std::vector<Vec3d> normals_;
};

// A muscle's grid of skin points: nu × nv, index i + j·nu; u periodic for a ring.
struct Grid {
  int nu = 0, nv = 0;
  bool periodic = false;
  std::vector<Vec3d> skin, normal;
  std::vector<double> depth;  // centre depth per u (m)
  double thickness = 0;
  std::size_t id(int i, int j) const { return static_cast<std::size_t>((i % nu) + j * nu); }
  Vec3d at(int i, int j, double offset) const {
    const auto k = id(i, j);
    return skin[k] - (depth[static_cast<std::size_t>(i % nu)] + offset * thickness) * normal[k];
  }
};

// Makes (∂u × ∂v) · n positive at the grid's middle by reversing v if needed, so that the quads
// (i, j), (i+1, j), (i+1, j+1), (i, j+1) run counter-clockwise seen from outside the skin.
void orient(Grid& g) {
  const int i = g.nu / 2, j = g.nv / 2;
  const Vec3d du = g.skin[g.id(i + 1, j)] - g.skin[g.id(i, j)];
  const Vec3d dv = g.skin[g.id(i, std::min(j + 1, g.nv - 1))] - g.skin[g.id(i, std::max(j - 1, 0))];
  if (dot(cross(du, dv), g.normal[g.id(i, j)]) >= 0) return;
  Grid r = g;
  for (int jj = 0; jj < g.nv; ++jj) {
    for (int ii = 0; ii < g.nu; ++ii) {
      r.skin[g.id(ii, jj)] = g.skin[g.id(ii, g.nv - 1 - jj)];
      r.normal[g.id(ii, jj)] = g.normal[g.id(ii, g.nv - 1 - jj)];
    }
  }
  g = std::move(r);
}

// Adds the quad (p0, p1, p2, p3), counter-clockwise seen from outside, as four triangles around
// its centre: no diagonal to choose, so a mirrored grid gives the mirrored triangles.
void add_quad(TriangleMesh& m, std::int32_t p0, std::int32_t p1, std::int32_t p2, std::int32_t p3) {
  const auto c = static_cast<std::int32_t>(m.vertices.size());
  const auto& v = m.vertices;
  m.vertices.push_back(0.25 * (v[static_cast<std::size_t>(p0)] + v[static_cast<std::size_t>(p1)] +
                               v[static_cast<std::size_t>(p2)] + v[static_cast<std::size_t>(p3)]));
  m.triangles.push_back({p0, p1, c});
  m.triangles.push_back({p1, p2, c});
  m.triangles.push_back({p2, p3, c});
  m.triangles.push_back({p3, p0, c});
}

// The closed slab between depth − thickness/2 (top) and depth + thickness/2 (bottom).
TriangleMesh slab(const Grid& g, const std::string& name) {
  TriangleMesh m;
  m.source = "rig: " + name;
  const auto n = static_cast<std::int32_t>(g.nu * g.nv);
  for (int j = 0; j < g.nv; ++j)
    for (int i = 0; i < g.nu; ++i) m.vertices.push_back(g.at(i, j, -0.5));
  for (int j = 0; j < g.nv; ++j)
    for (int i = 0; i < g.nu; ++i) m.vertices.push_back(g.at(i, j, 0.5));
  auto top = [&](int i, int j) { return static_cast<std::int32_t>(g.id(i, j)); };
  auto bot = [&](int i, int j) { return n + static_cast<std::int32_t>(g.id(i, j)); };
  const int cells_u = g.periodic ? g.nu : g.nu - 1;
  for (int j = 0; j + 1 < g.nv; ++j) {
    for (int i = 0; i < cells_u; ++i) {
      add_quad(m, top(i, j), top(i + 1, j), top(i + 1, j + 1), top(i, j + 1));
      add_quad(m, bot(i, j + 1), bot(i + 1, j + 1), bot(i + 1, j), bot(i, j));
    }
  }
  // Side walls along the boundary, traversed counter-clockwise seen from outside the skin.
  std::vector<std::pair<int, int>> loop;
  auto wall_loop = [&](const std::vector<std::pair<int, int>>& l, bool closed) {
    for (std::size_t k = 0; k + (closed ? 0 : 1) < l.size(); ++k) {
      const auto [i0, j0] = l[k];
      const auto [i1, j1] = l[(k + 1) % l.size()];
      add_quad(m, bot(i0, j0), bot(i1, j1), top(i1, j1), top(i0, j0));
    }
  };
  if (g.periodic) {
    std::vector<std::pair<int, int>> inner, outer;
    for (int i = 0; i < g.nu; ++i) inner.push_back({i, 0});
    for (int i = g.nu; i > 0; --i) outer.push_back({i % g.nu, g.nv - 1});
    wall_loop(inner, true);
    wall_loop(outer, true);
  } else {
    for (int i = 0; i < g.nu - 1; ++i) loop.push_back({i, 0});
    for (int j = 0; j < g.nv - 1; ++j) loop.push_back({g.nu - 1, j});
    for (int i = g.nu - 1; i > 0; --i) loop.push_back({i, g.nv - 1});
    for (int j = g.nv - 1; j > 0; --j) loop.push_back({0, j});
    wall_loop(loop, true);
  }
  return m;
}

int count_for(double length) {
  return std::max(3, static_cast<int>(std::ceil(length / kSpacing)) + 1);
}

Grid sheet_grid(const RigRecipe& r, const SkinProjector& skin) {
  Grid g;
  const double len = norm(r.insertion - r.origin);
  g.nu = std::max(4, count_for(len));
  g.nv = count_for(std::max(r.width_origin, r.width_insertion));
  g.thickness = r.thickness;
  // Onto the skin: the closest point, or along the recipe's axis when it has one (a midline
  // sheet, whose closest points could fall on either side of the midline).
  const bool along = norm(r.axis) > 0;
  auto onto = [&](const Vec3d& p) {
    return along ? skin.project_along(p, r.axis, 0.04) : skin.project(p);
  };
  std::vector<SkinProjector::Hit> centre(static_cast<std::size_t>(g.nu));
  for (int i = 0; i < g.nu; ++i) {
    const double s = static_cast<double>(i) / (g.nu - 1);
    centre[static_cast<std::size_t>(i)] = onto(r.origin + s * (r.insertion - r.origin));
    g.depth.push_back(r.depth_origin + s * (r.depth_insertion - r.depth_origin));
  }
  g.skin.resize(static_cast<std::size_t>(g.nu * g.nv));
  g.normal.resize(g.skin.size());
  for (int i = 0; i < g.nu; ++i) {
    const double s = static_cast<double>(i) / (g.nu - 1);
    const auto& c = centre[static_cast<std::size_t>(i)];
    const Vec3d tangent = centre[static_cast<std::size_t>(std::min(i + 1, g.nu - 1))].point -
                          centre[static_cast<std::size_t>(std::max(i - 1, 0))].point;
    const Vec3d across = unit(cross(c.normal, tangent));
    const double w = r.width_origin + s * (r.width_insertion - r.width_origin);
    for (int j = 0; j < g.nv; ++j) {
      const double t = static_cast<double>(j) / (g.nv - 1) - 0.5;
      const auto h = onto(c.point + (t * w) * across);
      g.skin[g.id(i, j)] = h.point;
      g.normal[g.id(i, j)] = h.normal;
    }
  }
  orient(g);
  return g;
}

Grid ring_grid(const RigRecipe& r, const SkinProjector& skin, Vec3d& axis, Vec3d& major,
               Vec3d& centre) {
  axis = r.axis;
  const auto c = skin.project_along(r.centre, axis, 0.04);
  major = unit(r.major - dot(r.major, axis) * axis);
  const Vec3d minor = cross(axis, major);
  Grid g;
  g.periodic = true;
  g.nu = 2 * std::max(12, static_cast<int>(std::ceil(std::numbers::pi * r.outer_a / kSpacing)));
  g.nv = count_for(std::max(r.outer_a - r.inner_a, r.outer_b - r.inner_b));
  g.thickness = r.thickness;
  g.depth.assign(static_cast<std::size_t>(g.nu), r.depth_origin);
  centre = c.point - r.depth_origin * axis;
  g.skin.resize(static_cast<std::size_t>(g.nu * g.nv));
  g.normal.resize(g.skin.size());
  for (int j = 0; j < g.nv; ++j) {
    const double rho = static_cast<double>(j) / (g.nv - 1);
    const double a = r.inner_a + rho * (r.outer_a - r.inner_a);
    const double b = r.inner_b + rho * (r.outer_b - r.inner_b);
    for (int i = 0; i < g.nu; ++i) {
      const double al = 2 * std::numbers::pi * i / g.nu;
      const auto h = skin.project_along(
          c.point + (a * std::cos(al)) * major + (b * std::sin(al)) * minor, axis, 0.04);
      g.skin[g.id(i, j)] = h.point;
      g.normal[g.id(i, j)] = h.normal;
    }
  }
  orient(g);
  return g;
}

Box end_box(const Grid& g, int i, double margin) {
  Box b{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}};
  for (int j = 0; j < g.nv; ++j) {
    for (const double o : {-0.5, 0.5}) {
      const Vec3d p = g.at(i, j, o);
      for (int d = 0; d < 3; ++d) {
        b.lo[d] = std::min(b.lo[d], p[d] - margin);
        b.hi[d] = std::max(b.hi[d], p[d] + margin);
      }
    }
  }
  return b;
}

std::vector<Vec3d> samples(const Grid& g) {
  std::vector<Vec3d> s;
  for (int j = 0; j < g.nv; ++j)
    for (int i = 0; i < g.nu; ++i)
      for (const double o : {-0.5, -0.25, 0.0, 0.25, 0.5}) s.push_back(g.at(i, j, o));
  return s;
}

std::string mm(double metres) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f mm", metres * 1e3);
  return buf;
}

}  // namespace

std::vector<RigMuscle> build_rig(const std::vector<RigRecipe>& recipes, const TriangleMesh& skin,
                                 double margin) {
  const SkinProjector projector(skin);
  std::vector<RigMuscle> out;
  for (const auto& r : recipes) {
    RigMuscle m;
    m.name = r.name;
    if (r.shape == RigRecipe::Shape::sheet) {
      const Grid g = sheet_grid(r, projector);
      m.mesh = slab(g, r.name);
      m.fibres.kind = FibreSpec::Kind::harmonic;
      m.fibres.origin.box = end_box(g, 0, margin);
      m.fibres.origin.field = "rig: " + r.name + " origin";
      m.fibres.insertion.box = end_box(g, g.nu - 1, margin);
      m.fibres.insertion.field = "rig: " + r.name + " insertion";
      m.samples = samples(g);
    } else {
      Vec3d axis, major, centre;
      const Grid g = ring_grid(r, projector, axis, major, centre);
      m.mesh = slab(g, r.name);
      m.fibres.kind = FibreSpec::Kind::circumferential;
      m.fibres.centre = centre;
      m.fibres.axis = axis;
      m.fibres.major = major;
      m.fibres.radius_major = 0.5 * (r.inner_a + r.outer_a);
      m.fibres.radius_minor = 0.5 * (r.inner_b + r.outer_b);
      m.samples = samples(g);
    }
    out.push_back(std::move(m));
  }
  return out;
}

std::vector<std::pair<std::string, double>> landmark_distances(const Landmarks& landmarks,
                                                               const TriangleMesh& skin) {
  const DistanceQuery q(skin);
  std::vector<std::pair<std::string, double>> d;
  for (const auto& name : landmark_names()) d.emplace_back(name, q.distance(landmarks.at(name)));
  return d;
}

Landmarks snap_landmarks(const Landmarks& landmarks, const TriangleMesh& skin) {
  const DistanceQuery q(skin);
  Landmarks snapped = landmarks;
  for (auto& [name, p] : snapped.points) p = q.closest(p).point;
  return snapped;
}

CheckedRig build_spec_rig(const Spec& spec) {
  const RigSpec& rig = *spec.rig;
  const Landmarks landmarks = read_landmarks(rig.landmarks);
  TriangleMesh skin = load_mesh_source(spec.outer);
  clean_mesh(skin, spec.weld_tolerance);

  std::string off;
  for (const auto& [name, d] : landmark_distances(landmarks, skin)) {
    if (d > rig.landmark_tolerance) {
      off += (off.empty() ? "" : ", ") + name + " is " + mm(d) + " off the skin";
    }
  }
  if (!off.empty()) {
    throw ConfigError(rig.landmarks.string(), "landmarks",
                      off + " (tolerance " + mm(rig.landmark_tolerance) + ", rig." +
                          "landmark_tolerance; skin " + spec.outer.describe() +
                          "): pick the points on this mesh, in its units (docs/landmarks.md)");
  }

  const double margin = spec.voxel_size ? *spec.voxel_size : 3e-3;
  const auto recipes = rig_recipes(landmarks, rig.muscles, rig.depth_scale);
  CheckedRig out;
  out.muscles = build_rig(recipes, skin, margin);

  // How much of each muscle lies in the tissue: inside the skin and outside the skull. Where the
  // rest lies says what to change: past the skin (an end beyond an open mesh's edge, where the
  // closest skin points stop: moving landmarks or covering the muscle helps, depths do not), in
  // the skull, or deeper than tissue_thickness (depths and thickness help).
  const WindingNumber outer(skin);
  const DistanceQuery beyond(skin);
  std::unique_ptr<WindingNumber> inner;
  std::unique_ptr<DistanceQuery> depth;
  if (spec.inner) {
    TriangleMesh k = load_mesh_source(*spec.inner);
    clean_mesh(k, spec.weld_tolerance);
    inner = std::make_unique<WindingNumber>(k);
  } else if (spec.tissue_thickness) {
    depth = std::make_unique<DistanceQuery>(skin);
  }
  std::string outside;
  bool past_skin = false, too_deep = false;
  for (std::size_t i = 0; i < out.muscles.size(); ++i) {
    const auto& m = out.muscles[i];
    std::int64_t in = 0, skin_out = 0, skull = 0, deep = 0;
    double farthest = 0;
    Vec3d where{0, 0, 0};
    for (const auto& p : m.samples) {
      if (!outer.inside(p)) {
        ++skin_out;
        const double d = beyond.distance(p);
        if (d > farthest) farthest = d, where = p;
      } else if (inner && inner->inside(p)) {
        ++skull;
      } else if (depth && depth->distance(p) > *spec.tissue_thickness) {
        ++deep;
      } else {
        ++in;
      }
    }
    const double n = static_cast<double>(m.samples.size());
    const double share = static_cast<double>(in) / n;
    log::debug("rig: {} {:.1f}% inside the tissue", m.name, 100 * share);
    if (share >= rig.min_inside) continue;
    char buf[320];
    std::snprintf(buf, sizeof buf, "%s only %.0f%% inside", m.name.c_str(), 100 * share);
    std::string item = buf;
    std::string parts;
    const auto part = [&](std::int64_t k, const char* where_text) {
      if (k == 0) return;
      std::snprintf(buf, sizeof buf, "%.0f%% %s", 100 * static_cast<double>(k) / n, where_text);
      parts += (parts.empty() ? "" : ", ") + std::string(buf);
    };
    part(skin_out, "outside the skin");
    if (skin_out > 0) {
      // Which end: the recipe's origin or insertion (a ring: around its centre).
      const RigRecipe& r = recipes[i];
      std::string end = "around its centre";
      if (r.shape == RigRecipe::Shape::sheet)
        end = norm(where - r.origin) <= norm(where - r.insertion) ? "nearest its origin"
                                                                  : "nearest its insertion";
      parts += ", up to " + mm(farthest) + " beyond it " + end;
      past_skin = past_skin || skin_out >= skull + deep;
    }
    part(skull, "in the skull");
    part(deep, "deeper than tissue_thickness");
    too_deep = too_deep || skull + deep > skin_out;
    outside += (outside.empty() ? "" : ", ") + item + " (" + parts + ")";
  }
  if (!outside.empty()) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.0f%%", 100 * rig.min_inside);
    std::string advice;
    if (past_skin) {
      advice +=
          "; a muscle past the skin has an end beyond the mesh (an open mesh such as a face "
          "mask stops the muscle at its edge): move the landmarks that end is built from "
          "(docs/faces.md lists each muscle's) inside the mesh, or use a mesh that covers the "
          "muscle; the tissue's thickness and rig.depth_scale do not change this";
    }
    if (too_deep) {
      advice +=
          "; for a muscle in the skull or too deep, check the landmarks, or the tissue's "
          "thickness, or scale the depths with rig.depth_scale";
    }
    out.message = "rig muscles outside the tissue (skin to skull): " + outside + " (at least " +
                  buf + " needed, rig.min_inside)" + advice;
  }
  return out;
}

void add_rig_muscles(Spec& spec) {
  if (!spec.rig) return;
  const CheckedRig built = build_spec_rig(spec);
  if (!built.message.empty())
    throw GeometryError(spec.file.string(), spec.rig->field, built.message);
  append_rig_muscles(spec, built);
}

void append_rig_muscles(Spec& spec, const CheckedRig& built) {
  const RigSpec& rig = *spec.rig;
  const auto& muscles = built.muscles;

  for (const auto& m : muscles) {
    for (const auto& other : spec.muscles) {
      if (other.name == m.name) {
        throw ConfigError(spec.file.string(), rig.field,
                          "the rig builds muscle '" + m.name +
                              "', which the spec's muscles list too: remove one");
      }
    }
    MuscleSpec s;
    s.name = m.name;
    s.mesh.kind = MeshSource::Kind::generated;
    s.mesh.generated = std::make_shared<const TriangleMesh>(m.mesh);
    s.mesh.field = rig.field + "." + m.name;
    s.material = rig.material;
    s.reference_stress = rig.reference_stress;
    s.fibres = m.fibres;
    spec.muscles.push_back(std::move(s));
  }
}

}  // namespace sinew::voxelizer
