#include "sinew/voxelizer/forehead.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <numbers>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::voxelizer {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double gauss(double x, double width) {
  return std::exp(-(x / width) * (x / width));
}

Vec3d ellipsoid_point(const ForeheadParams& p, double th, double ph) {
  return {p.skull_half_width * std::sin(th) * std::cos(ph), p.skull_vertical_radius * std::sin(ph),
          p.skull_depth * std::cos(th) * std::cos(ph)};
}

Vec3d ellipsoid_normal(const ForeheadParams& p, const Vec3d& e) {
  const Vec3d g{e.x / (p.skull_half_width * p.skull_half_width),
                e.y / (p.skull_vertical_radius * p.skull_vertical_radius),
                e.z / (p.skull_depth * p.skull_depth)};
  return (1.0 / norm(g)) * g;
}

// A height function h(θ, φ) (mm above the skull) over a rectangle of (θ, φ) in degrees, sampled
// at parameters a, b ∈ [0, 1].
struct Sheet {
  std::function<Vec3d(double a, double b)> angles;  // (θ, φ, unused) in degrees
  std::function<double(double theta, double phi)> height;
};

Vec3d sheet_point(const ForeheadParams& p, const Sheet& s, double a, double b) {
  const Vec3d ang = s.angles(a, b);
  const double h = s.height(ang.x, ang.y);
  return forehead_skull_point(p, ang.x, ang.y) + h * forehead_skull_normal(p, ang.x, ang.y);
}

std::vector<double> uniform_samples(int n) {
  std::vector<double> s(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) s[static_cast<std::size_t>(i)] = static_cast<double>(i) / (n - 1);
  return s;
}

// Vertices needed along a parameter so that edges are about `spacing` long on the sheet.
int sample_count(const ForeheadParams& p, const Sheet& s, bool along_a, double spacing) {
  constexpr int kSteps = 256;
  double len = 0;
  Vec3d prev = along_a ? sheet_point(p, s, 0, 0.5) : sheet_point(p, s, 0.5, 0);
  for (int k = 1; k <= kSteps; ++k) {
    const double t = static_cast<double>(k) / kSteps;
    const Vec3d q = along_a ? sheet_point(p, s, t, 0.5) : sheet_point(p, s, 0.5, t);
    len += norm(q - prev);
    prev = q;
  }
  return std::max(2, static_cast<int>(std::ceil(len / spacing)) + 1);
}

struct Grid {
  std::vector<double> a, b;  // samples, each from 0 to 1
};

// The boundary of a grid's vertex block (indices base + i + j·na) counter-clockwise in (a, b),
// starting at (0, 0), with the perimeter parameter in [0, 4) of each vertex.
void grid_ring(const Grid& g, std::int32_t base, std::vector<std::int32_t>& ids,
               std::vector<double>& t) {
  const int na = static_cast<int>(g.a.size()), nb = static_cast<int>(g.b.size());
  auto id = [&](int i, int j) { return base + i + j * na; };
  for (int i = 0; i < na - 1; ++i) ids.push_back(id(i, 0)), t.push_back(g.a[i]);
  for (int j = 0; j < nb - 1; ++j) ids.push_back(id(na - 1, j)), t.push_back(1 + g.b[j]);
  for (int i = na - 1; i > 0; --i) ids.push_back(id(i, nb - 1)), t.push_back(3 - g.a[i]);
  for (int j = nb - 1; j > 0; --j) ids.push_back(id(0, j)), t.push_back(4 - g.b[j]);
}

void add_grid(TriangleMesh& m, const ForeheadParams& p, const Sheet& s, const Grid& g,
              bool outward_up) {
  const auto base = static_cast<std::int32_t>(m.vertices.size());
  const int na = static_cast<int>(g.a.size()), nb = static_cast<int>(g.b.size());
  for (int j = 0; j < nb; ++j) {
    for (int i = 0; i < na; ++i) m.vertices.push_back(sheet_point(p, s, g.a[i], g.b[j]));
  }
  for (int j = 0; j + 1 < nb; ++j) {
    for (int i = 0; i + 1 < na; ++i) {
      const std::int32_t v00 = base + i + j * na, v10 = v00 + 1, v01 = v00 + na, v11 = v01 + 1;
      // Alternate the diagonal so that the triangulation has no preferred direction.
      const bool flip = ((i + j) % 2) == 1;
      std::array<std::int32_t, 3> t1, t2;
      if (!flip) {
        t1 = {v00, v10, v11};
        t2 = {v00, v11, v01};
      } else {
        t1 = {v00, v10, v01};
        t2 = {v10, v11, v01};
      }
      if (!outward_up) {
        std::swap(t1[1], t1[2]);
        std::swap(t2[1], t2[2]);
      }
      m.triangles.push_back(t1);
      m.triangles.push_back(t2);
    }
  }
}

// A closed slab: `top` sheet over grid gt (outward away from the skull), `bottom` sheet over grid
// gb (outward towards the skull), side walls zipping the two boundary rings. Both sheets share the
// (a, b) → angles map, so the rings run over the same rectangle edges. Oriented outward.
TriangleMesh make_slab(const ForeheadParams& p, const Sheet& top, const Grid& gt,
                       const Sheet& bottom, const Grid& gb, const std::string& name) {
  TriangleMesh m;
  m.source = name;
  add_grid(m, p, top, gt, true);
  const auto bottom_base = static_cast<std::int32_t>(m.vertices.size());
  add_grid(m, p, bottom, gb, false);
  std::vector<std::int32_t> T, B;
  std::vector<double> tT, tB;
  grid_ring(gt, 0, T, tT);
  grid_ring(gb, bottom_base, B, tB);
  const std::size_t nt = T.size(), nbr = B.size();
  std::size_t i = 0, j = 0;
  while (i < nt || j < nbr) {
    const double next_t = i + 1 < nt ? tT[i + 1] : 4.0;
    const double next_b = j + 1 < nbr ? tB[j + 1] : 4.0;
    const bool advance_top = j == nbr || (i < nt && next_t <= next_b);
    if (advance_top) {
      m.triangles.push_back({B[j % nbr], T[(i + 1) % nt], T[i % nt]});
      ++i;
    } else {
      m.triangles.push_back({B[j % nbr], B[(j + 1) % nbr], T[i % nt]});
      ++j;
    }
  }
  if (describe_mesh(m).enclosed_volume < 0) {
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  }
  return m;
}

Grid uniform_grid(const ForeheadParams& p, const Sheet& s, double spacing) {
  return {uniform_samples(sample_count(p, s, true, spacing)),
          uniform_samples(sample_count(p, s, false, spacing))};
}

double lerp(double a, double b, double t) {
  return a + (b - a) * t;
}

// Degrees of yaw per mm along the skull at elevation φ (near the front, ds/dθ ≈ A cos φ).
double yaw_deg_per_mm(const ForeheadParams& p, double phi_deg) {
  return 1.0 / (p.skull_half_width * std::cos(phi_deg * kDeg) * kDeg);
}

Sheet skin_top_sheet(const ForeheadParams& p) {
  return {[&p](double a, double b) {
            return Vec3d{lerp(-p.patch_half_angle_deg, p.patch_half_angle_deg, a),
                         lerp(p.patch_bottom_deg, p.patch_top_deg, b), 0};
          },
          [&p](double th, double ph) { return forehead_thickness(p, th, ph); }};
}

Sheet with_height(Sheet s, double h) {
  s.height = [h](double, double) { return h; };
  return s;
}

TriangleMesh muscle_mesh(const ForeheadParams& p, double side) {
  Sheet mid{[&p, side](double a, double b) {
              const double ph = lerp(p.muscle_bottom_deg, p.muscle_top_deg, b);
              const double medial =
                  lerp(p.medial_gap_bottom, p.medial_gap_top, b) * yaw_deg_per_mm(p, ph);
              return Vec3d{side * lerp(medial, p.muscle_lateral_deg, a), ph, 0};
            },
            [&p](double, double) { return p.muscle_height; }};
  const Grid g = uniform_grid(p, mid, p.spacing);
  const Sheet top = with_height(mid, p.muscle_height + 0.5 * p.muscle_thickness);
  const Sheet bottom = with_height(mid, p.muscle_height - 0.5 * p.muscle_thickness);
  return make_slab(p, top, g, bottom, g, side > 0 ? "frontalis_right" : "frontalis_left");
}

void need(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw ConfigError("", field, problem);
}

}  // namespace

Vec3d forehead_skull_point(const ForeheadParams& p, double theta_deg, double phi_deg) {
  const Vec3d e = ellipsoid_point(p, theta_deg * kDeg, phi_deg * kDeg);
  const double r = p.ridge_height * gauss(phi_deg - p.ridge_deg, p.ridge_width_deg) *
                   (gauss(theta_deg - p.ridge_yaw_deg, p.ridge_spread_deg) +
                    gauss(theta_deg + p.ridge_yaw_deg, p.ridge_spread_deg));
  return e + r * ellipsoid_normal(p, e);
}

Vec3d forehead_skull_normal(const ForeheadParams& p, double theta_deg, double phi_deg) {
  constexpr double d = 1e-3;  // degrees
  const Vec3d st = forehead_skull_point(p, theta_deg + d, phi_deg) -
                   forehead_skull_point(p, theta_deg - d, phi_deg);
  const Vec3d sp = forehead_skull_point(p, theta_deg, phi_deg + d) -
                   forehead_skull_point(p, theta_deg, phi_deg - d);
  const Vec3d n = cross(st, sp);
  return (1.0 / norm(n)) * n;
}

double forehead_thickness(const ForeheadParams& p, double theta_deg, double phi_deg) {
  const double q = theta_deg / p.patch_half_angle_deg;
  return p.thickness_mid +
         (p.thickness_brow - p.thickness_mid) * gauss(phi_deg - p.brow_deg, p.brow_width_deg) -
         p.temple_thinning * q * q;
}

void check_forehead_params(const ForeheadParams& p) {
  for (const auto& [v, name] : std::initializer_list<std::pair<double, const char*>>{
           {p.skull_half_width, "skull_half_width"},
           {p.skull_vertical_radius, "skull_vertical_radius"},
           {p.skull_depth, "skull_depth"},
           {p.ridge_width_deg, "ridge_width_deg"},
           {p.ridge_spread_deg, "ridge_spread_deg"},
           {p.patch_half_angle_deg, "patch_half_angle_deg"},
           {p.thickness_mid, "thickness_mid"},
           {p.thickness_brow, "thickness_brow"},
           {p.brow_width_deg, "brow_width_deg"},
           {p.muscle_height, "muscle_height"},
           {p.muscle_thickness, "muscle_thickness"},
           {p.muscle_lateral_deg, "muscle_lateral_deg"},
           {p.galea_height, "galea_height"},
           {p.galea_thickness, "galea_thickness"},
           {p.galea_half_angle_deg, "galea_half_angle_deg"},
           {p.skin_base_depth, "skin_base_depth"},
           {p.skull_cap_depth, "skull_cap_depth"},
           {p.skull_margin, "skull_margin"},
           {p.spacing, "spacing"},
           {p.surface_spacing, "surface_spacing"},
           {p.glide_depth, "glide_depth"},
           {p.glide_thickness, "glide_thickness"},
           {p.glide_margin, "glide_margin"},
           {p.glide_depth_coarse, "glide_depth_coarse"},
           {p.glide_spacing, "glide_spacing"}}) {
    need(std::isfinite(v) && v > 0, name, "must be a finite number > 0, got " + std::to_string(v));
  }
  need(p.ridge_height >= 0, "ridge_height", "must be >= 0");
  need(p.temple_thinning >= 0, "temple_thinning", "must be >= 0");
  need(p.medial_gap_bottom >= 0 && p.medial_gap_top >= 0, "medial_gap_bottom",
       "medial gaps must be >= 0");
  need(p.patch_half_angle_deg < 85, "patch_half_angle_deg", "must be below 85 degrees");
  need(p.patch_bottom_deg > -60 && p.patch_top_deg < 75 && p.patch_bottom_deg < p.patch_top_deg,
       "patch_top_deg", "need -60 < patch_bottom_deg < patch_top_deg < 75");
  need(p.muscle_bottom_deg > p.patch_bottom_deg && p.muscle_top_deg < p.patch_top_deg &&
           p.muscle_bottom_deg < p.muscle_top_deg,
       "muscle_top_deg", "the muscle's elevation range must lie inside the patch's");
  need(p.muscle_lateral_deg < p.patch_half_angle_deg, "muscle_lateral_deg",
       "must be below patch_half_angle_deg");
  need(p.galea_bottom_deg > p.patch_bottom_deg && p.galea_top_deg < p.patch_top_deg &&
           p.galea_bottom_deg < p.galea_top_deg,
       "galea_top_deg", "the galea's elevation range must lie inside the patch's");
  need(p.galea_half_angle_deg < p.patch_half_angle_deg, "galea_half_angle_deg",
       "must be below patch_half_angle_deg");
  const double t_min = p.thickness_mid - p.temple_thinning;
  need(t_min > 0, "temple_thinning", "leaves no tissue at the temples");
  need(p.muscle_height - 0.5 * p.muscle_thickness > 0 &&
           p.muscle_height + 0.5 * p.muscle_thickness < t_min,
       "muscle_height", "the muscle sheet must lie between the skull and the skin");
  need(p.galea_height - 0.5 * p.galea_thickness > 0 &&
           p.galea_height + 0.5 * p.galea_thickness < t_min,
       "galea_height", "the galea must lie between the skull and the skin");
  need(p.skull_cap_depth > p.skin_base_depth, "skull_cap_depth",
       "must exceed skin_base_depth (the skin's bottom lies inside the skull cap)");
  const double lateral_medial =
      lerp(p.medial_gap_bottom, p.medial_gap_top, 1.0) * yaw_deg_per_mm(p, p.muscle_top_deg);
  need(lateral_medial < p.muscle_lateral_deg, "medial_gap_top",
       "the medial edge must stay medial of muscle_lateral_deg");
}

ForeheadMeshes make_forehead(const ForeheadParams& p) {
  check_forehead_params(p);
  ForeheadMeshes out;

  // Skin: the tissue's top over the patch, closed by walls down into the skull cap and a coarse
  // bottom there.
  const Sheet skin_top = skin_top_sheet(p);
  const Grid g_skin = uniform_grid(p, skin_top, p.spacing);
  const Grid g_coarse = uniform_grid(p, skin_top, 8 * p.spacing);
  out.skin =
      make_slab(p, skin_top, g_skin, with_height(skin_top, -p.skin_base_depth), g_coarse, "skin");
  out.skin_surface.source = "skin_surface";
  add_grid(out.skin_surface, p, skin_top, uniform_grid(p, skin_top, p.surface_spacing), true);

  // Skull cap: the skull surface over the patch shrunk by kSkullInset (the skin's samples), so that
  // its top rim lies just inside the skin's side walls; its walls run outward and down to a coarse
  // bottom over the patch widened by the margin, so that the cap covers the skin's bottom and only
  // the cap's bottom lies outside the skin. The sliver of tissue left between the two walls is
  // kSkullInset wide and a few hundredths of a mm tall.
  constexpr double kSkullInset = 0.05;  // mm
  const double in_theta = kSkullInset * yaw_deg_per_mm(p, p.patch_top_deg);
  const double in_phi = kSkullInset / (p.skull_vertical_radius * kDeg);
  const double out_theta = p.skull_margin * yaw_deg_per_mm(p, p.patch_bottom_deg);
  const double out_phi = p.skull_margin / (p.skull_vertical_radius * kDeg);
  auto rectangle = [&p](double d_theta, double d_phi) {
    const double th0 = -p.patch_half_angle_deg - d_theta, th1 = p.patch_half_angle_deg + d_theta;
    const double ph0 = p.patch_bottom_deg - d_phi, ph1 = p.patch_top_deg + d_phi;
    return Sheet{[=](double a, double b) {
                   return Vec3d{lerp(th0, th1, a), lerp(ph0, ph1, b), 0};
                 },
                 [](double, double) { return 0.0; }};
  };
  const Sheet cap_top = rectangle(-in_theta, -in_phi);
  const Sheet cap_bottom = with_height(rectangle(out_theta, out_phi), -p.skull_cap_depth);
  out.skull = make_slab(p, cap_top, g_skin, cap_bottom, uniform_grid(p, cap_bottom, 8 * p.spacing),
                        "skull");
  // Wider than the cap, so that every node near the patch's rim (up to sqrt(3) h outside it) has
  // its closest point on the glide surface's top, not on its walls.
  const Sheet glide = rectangle(p.glide_margin * yaw_deg_per_mm(p, p.patch_top_deg),
                                p.glide_margin / (p.skull_vertical_radius * kDeg));
  auto glide_mesh = [&](double depth, const char* name) {
    return make_slab(p, with_height(glide, -depth), uniform_grid(p, glide, p.glide_spacing),
                     with_height(glide, -depth - p.glide_thickness),
                     uniform_grid(p, glide, 8 * p.glide_spacing), name);
  };
  out.skull_glide = glide_mesh(p.glide_depth, "skull_glide");
  out.skull_glide_coarse = glide_mesh(p.glide_depth_coarse, "skull_glide_coarse");

  out.frontalis_right = muscle_mesh(p, +1.0);
  out.frontalis_left = muscle_mesh(p, -1.0);

  Sheet galea_mid{[&p](double a, double b) {
                    return Vec3d{lerp(-p.galea_half_angle_deg, p.galea_half_angle_deg, a),
                                 lerp(p.galea_bottom_deg, p.galea_top_deg, b), 0};
                  },
                  [&p](double, double) { return p.galea_height; }};
  const Grid g_galea = uniform_grid(p, galea_mid, p.spacing);
  out.galea =
      make_slab(p, with_height(galea_mid, p.galea_height + 0.5 * p.galea_thickness), g_galea,
                with_height(galea_mid, p.galea_height - 0.5 * p.galea_thickness), g_galea, "galea");
  return out;
}

ForeheadLandmarks forehead_landmarks(const ForeheadParams& p) {
  check_forehead_params(p);
  ForeheadLandmarks l;
  auto skin = [&p](double th, double ph) {
    return forehead_skull_point(p, th, ph) +
           forehead_thickness(p, th, ph) * forehead_skull_normal(p, th, ph);
  };
  l.brow_centre = skin(0, p.brow_deg);
  l.hairline_centre = skin(0, p.galea_bottom_deg);
  constexpr int kSteps = 512;
  for (int k = 0; k < kSteps; ++k) {
    const double s0 = static_cast<double>(k) / kSteps, s1 = static_cast<double>(k + 1) / kSteps;
    l.width += norm(skin(lerp(-p.patch_half_angle_deg, p.patch_half_angle_deg, s1), p.brow_deg) -
                    skin(lerp(-p.patch_half_angle_deg, p.patch_half_angle_deg, s0), p.brow_deg));
    l.height += norm(skin(0, lerp(p.patch_bottom_deg, p.patch_top_deg, s1)) -
                     skin(0, lerp(p.patch_bottom_deg, p.patch_top_deg, s0)));
  }
  const BoundingBox box = bounding_box(make_forehead(p).skin);
  l.lo = box.lo;
  l.hi = box.hi;
  return l;
}

std::string obj_text(const TriangleMesh& mesh, const std::vector<std::string>& comments) {
  std::string s;
  s.reserve(mesh.vertices.size() * 32 + mesh.triangles.size() * 24 + 256);
  for (const auto& c : comments) s += "# " + c + "\n";
  char buf[96];
  for (const auto& v : mesh.vertices) {
    // Avoid "-0.0000" so that the text does not depend on the sign of a rounded zero.
    auto clean = [](double x) { return std::abs(x) < 5e-4 ? 0.0 : x; };
    std::snprintf(buf, sizeof buf, "v %.3f %.3f %.3f\n", clean(v.x), clean(v.y), clean(v.z));
    s += buf;
  }
  for (const auto& t : mesh.triangles) {
    std::snprintf(buf, sizeof buf, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
    s += buf;
  }
  return s;
}

std::vector<std::string> forehead_file_names() {
  return {"skull.obj",        "skull_glide.obj",    "skull_glide_coarse.obj", "skin.obj",
          "skin_surface.obj", "frontalis_left.obj", "frontalis_right.obj",    "galea.obj"};
}

std::vector<std::filesystem::path> write_forehead(const ForeheadParams& p,
                                                  const std::filesystem::path& dir) {
  const ForeheadMeshes m = make_forehead(p);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir.string(), "", "cannot create the folder: " + ec.message());
  const std::vector<const TriangleMesh*> meshes{
      &m.skull,        &m.skull_glide,    &m.skull_glide_coarse, &m.skin,
      &m.skin_surface, &m.frontalis_left, &m.frontalis_right,    &m.galea};
  const auto names = forehead_file_names();
  std::vector<std::filesystem::path> written;
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const auto path = dir / names[k];
    const bool closed = names[k] != "skin_surface.obj";
    const std::string text = obj_text(
        *meshes[k], {"sinew-forehead: " + meshes[k]->source + " (docs/forehead.md)",
                     "units: mm; x right, y up, z forward",
                     closed ? "closed, outward oriented" : "open: the skin's top surface"});
    write_text_atomically(path.string(), text);
    written.push_back(path);
  }
  return written;
}

}  // namespace sinew::voxelizer
