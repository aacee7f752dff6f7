#include "sinew/voxelizer/head.hpp"

#include <cmath>
#include <numbers>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/voxelizer/forehead.hpp"

namespace sinew::voxelizer {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double g(double u, double w) {
  return std::exp(-(u / w) * (u / w));
}
// A pair of bumps at θ = ±t0: symmetric in θ by construction (addition commutes exactly).
double pair(double th, double t0, double w) {
  return g(th - t0, w) + g(th + t0, w);
}
double smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3 - 2 * t);
}

// Where the landmarks sit (degrees), at ±θ for the two sides.
constexpr double kBrowPhi = 18, kEyePhi = 8, kEyeTheta = 20, kEyeHalf = 9.5;
constexpr double kTipPhi = -14, kAlarPhi = -19, kAlarTheta = 9;
constexpr double kUpperLipPhi = -31, kLowerLipPhi = -40, kMouthPhi = -35.5, kMouthTheta = 21;
constexpr double kChinPhi = -56, kCheekTheta = 36, kCheekPhi = -4, kHairPhi = 40;

// Bone relief b(θ, φ), mm along n_E.
double bone(double th, double ph) {
  const double lower_face = 24 * g(ph + 45, 20) * g(th, 40);
  const double brow_ridge = 4 * g(ph - kBrowPhi, 6) * (pair(th, 17, 13) + 0.6 * g(th, 10));
  const double cheekbones = 5 * pair(th, kCheekTheta, 12) * g(ph - kCheekPhi, 9);
  const double eye_sockets = -6 * pair(th, kEyeTheta, 10) * g(ph - kEyePhi, 7);
  return lower_face + brow_ridge + cheekbones + eye_sockets;
}

// Soft relief s(θ, φ), mm along n_E: nose, lips, chin pad.
double soft(double th, double ph) {
  // Nose: the dorsum rises from the nasion (φ = 12) to the tip, then falls to the columella.
  const double rise = smoothstep((12 - ph) / (12 - kTipPhi));
  const double height = ph >= kTipPhi ? 18 * rise : 18 * g(ph - kTipPhi, 4.5);
  const double width = 4 + 5 * rise;
  const double nose = height * g(th, width) + 5 * pair(th, kAlarTheta, 4.5) * g(ph - kAlarPhi, 4);
  const double lips = 5 * g(th, 19) * g(ph - kUpperLipPhi, 4) +
                      5 * g(th, 17) * g(ph - kLowerLipPhi, 4) -
                      1.5 * g(th, 18) * g(ph - kMouthPhi, 1.5);
  const double chin = 5 * g(th, 14) * g(ph - kChinPhi, 7);
  return nose + lips + chin;
}

// Soft-tissue thickness over the skull, nose and lips aside (they are soft relief), mm.
double tissue(const HeadParams& p, double th, double ph) {
  return p.tissue_base + p.tissue_cheek * pair(th, 32, 16) * g(ph + 18, 16) +
         p.tissue_lips * g(th, 25) * g(ph - kMouthPhi, 9) +
         p.tissue_chin * g(th, 18) * g(ph - kChinPhi, 9) +
         p.tissue_orbit * pair(th, kEyeTheta, 10) * g(ph - kEyePhi, 7);
}

struct Frame {
  Vec3d e, n;  // ellipsoid point and its outward unit normal
};

Frame ellipsoid(const HeadParams& p, double th_deg, double ph_deg) {
  const double th = th_deg * kDeg, ph = ph_deg * kDeg;
  const Vec3d e{p.half_width * std::sin(th) * std::cos(ph), p.half_height * std::sin(ph),
                p.half_depth * std::cos(th) * std::cos(ph)};
  const Vec3d grad{e.x / (p.half_width * p.half_width), e.y / (p.half_height * p.half_height),
                   e.z / (p.half_depth * p.half_depth)};
  return {e, (1.0 / norm(grad)) * grad};
}

// A closed mesh over the (θ, φ) sphere: rings of segments_around vertices at every inner
// elevation, one vertex at each pole.
TriangleMesh sphere_mesh(const HeadParams& p, const std::string& name,
                         Vec3d (*point)(const HeadParams&, double, double)) {
  const int na = p.segments_around, nu = p.segments_up;
  const double da = 360.0 / na, du = 180.0 / nu;
  TriangleMesh m;
  m.source = name;
  m.vertices.push_back(point(p, 0, -90));
  for (int j = 1; j < nu; ++j) {
    // θ_k = (k − na/2) Δ: the mirror of vertex k is vertex na − k, with exactly −θ_k.
    for (int k = 0; k < na; ++k) m.vertices.push_back(point(p, (k - na / 2) * da, -90 + j * du));
  }
  m.vertices.push_back(point(p, 0, 90));
  const auto top = static_cast<std::int32_t>(m.vertices.size() - 1);
  auto id = [&](int j, int k) { return static_cast<std::int32_t>(1 + (j - 1) * na + (k % na)); };
  // Counter-clockwise seen from outside: with θ increasing to +x at the front and φ upward, the
  // outward order of a quad is (j, k), (j, k+1), (j+1, k+1), (j+1, k).
  for (int k = 0; k < na; ++k) m.triangles.push_back({0, id(1, k + 1), id(1, k)});
  for (int j = 1; j + 1 < nu; ++j) {
    for (int k = 0; k < na; ++k) {
      const auto a = id(j, k), b = id(j, k + 1), c = id(j + 1, k + 1), d = id(j + 1, k);
      // The mirror of quad k is quad na − 1 − k, of the other parity: it takes the other
      // diagonal, which is the mirror image of this one.
      if ((k + j) % 2 == 0) {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
      } else {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({b, c, d});
      }
    }
  }
  for (int k = 0; k < na; ++k) m.triangles.push_back({top, id(nu - 1, k), id(nu - 1, k + 1)});
  return m;
}

}  // namespace

void check_head_params(const HeadParams& p) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0)) throw ConfigError("", name, "must be > 0");
  };
  positive(p.half_width, "half_width");
  positive(p.half_height, "half_height");
  positive(p.half_depth, "half_depth");
  positive(p.tissue_base, "tissue_base");
  positive(p.glide_depth, "glide_depth");
  for (auto [v, name] : {std::pair{p.tissue_cheek, "tissue_cheek"},
                         {p.tissue_lips, "tissue_lips"},
                         {p.tissue_chin, "tissue_chin"},
                         {p.tissue_orbit, "tissue_orbit"}}) {
    if (!(v >= 0)) throw ConfigError("", name, "must be >= 0");
  }
  for (auto [v, name] :
       {std::pair{p.segments_around, "segments_around"}, {p.segments_up, "segments_up"}}) {
    if (v < 16 || v % 2 != 0) throw ConfigError("", name, "must be even and at least 16");
  }
}

Vec3d head_skin_point(const HeadParams& p, double th, double ph) {
  const Frame f = ellipsoid(p, th, ph);
  return f.e + (bone(th, ph) + soft(th, ph)) * f.n;
}

Vec3d head_skull_point(const HeadParams& p, double th, double ph) {
  const Frame f = ellipsoid(p, th, ph);
  return f.e + (bone(th, ph) - tissue(p, th, ph)) * f.n;
}

Vec3d head_glide_point(const HeadParams& p, double th, double ph) {
  const Frame f = ellipsoid(p, th, ph);
  return f.e + (bone(th, ph) - tissue(p, th, ph) - p.glide_depth) * f.n;
}

HeadMeshes make_head(const HeadParams& p) {
  check_head_params(p);
  return {sphere_mesh(p, "sample head skin", &head_skin_point),
          sphere_mesh(p, "sample head skull", &head_skull_point),
          sphere_mesh(p, "sample head skull glide surface", &head_glide_point)};
}

Landmarks head_landmarks(const HeadParams& p) {
  Landmarks l;
  l.mesh = "skin.obj";
  auto put = [&](const std::string& name, double th, double ph) {
    l.points[name] = 1e-3 * head_skin_point(p, th, ph);
  };
  auto both = [&](const std::string& name, double th, double ph) {
    // The subject's right is at x < 0 (θ < 0): a camera on +z sees it on the image's left.
    put(name + "_right", -th, ph);
    put(name + "_left", th, ph);
  };
  put("hairline", 0, kHairPhi);
  put("glabella", 0, kBrowPhi - 2);
  both("brow_centre", kEyeTheta, kBrowPhi);
  both("eye_inner", kEyeTheta - kEyeHalf, kEyePhi);
  both("eye_outer", kEyeTheta + kEyeHalf, kEyePhi);
  put("nose_tip", 0, kTipPhi);
  both("alar_base", kAlarTheta + 4.5, kAlarPhi);
  both("cheekbone", kCheekTheta, kCheekPhi);
  both("tragus", 86, 2);
  put("upper_lip", 0, kUpperLipPhi);
  put("lower_lip", 0, kLowerLipPhi);
  both("mouth_corner", kMouthTheta, kMouthPhi);
  put("chin", 0, kChinPhi);
  return l;
}

std::vector<std::filesystem::path> write_head(const HeadParams& p,
                                              const std::filesystem::path& dir) {
  const HeadMeshes m = make_head(p);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw IoError(dir.string(), "", "cannot create the folder: " + ec.message());
  std::vector<std::filesystem::path> written;
  for (const auto& [mesh, file] : {std::pair{&m.skin, "skin.obj"},
                                   {&m.skull, "skull.obj"},
                                   {&m.skull_glide, "skull_glide.obj"}}) {
    const auto path = dir / file;
    write_text_atomically(path.string(),
                          obj_text(*mesh, {"sinew-head: " + mesh->source + " (docs/faces.md)",
                                           "units: mm; x to the subject's left, y up, z forward",
                                           "closed, outward oriented"}));
    written.push_back(path);
  }
  const auto lpath = dir / "landmarks.yaml";
  write_text_atomically(
      lpath.string(), landmarks_yaml(head_landmarks(p), LengthUnit::mm,
                                     {"sinew-head: the sample head's landmarks (docs/landmarks.md)",
                                      "on skin.obj; x to the subject's left, y up, z forward "
                                      "(the face looks along +z)"}));
  written.push_back(lpath);
  return written;
}

}  // namespace sinew::voxelizer
