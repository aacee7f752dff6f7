// Wrinkle measurement (export/wrinkles.hpp, docs/wrinkles.md): synthetic sheets with known
// sinusoidal wrinkles on a curved, globally displaced surface; the detrending's transfer function;
// bad input; and sinew-wrinkles end to end on a small results file.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/postprocess/wrinkles.hpp"
#include "sinew/simulator/output/results_writer.hpp"

namespace {

using namespace sinew::postprocess;
namespace fs = std::filesystem;
namespace h5 = sinew::formats::hdf5;
constexpr double kPi = std::numbers::pi;

// A sheet curved both ways: across x a parabola of radius Rx, along y a circle of radius R about
// the x axis, so that the rest arc length along a profile x = const is exactly s = R θ:
//   P(x, s) = (x, R sin(s/R), R cos(s/R) − R − x²/(2 Rx)),  up = +z.
// Deformed: the material point (x, s) moves to the sheet point (x, s') with s' = (1 + ε) s + shift
// (a uniform compression ε along the profile plus a slide), is lifted along the sheet normal by
// a smooth bulge B cos(π s / 60 mm) plus the wrinkle A cos(2π s / λ + φ), and the whole sheet is
// translated by T. The deformed smooth arc length between consecutive troughs is (1 + ε) λ and the
// peak-to-trough depth is 2A.
struct Sheet {
  double half = 0.030;   // x, s in [−half, half], m
  double step = 0.0004;  // vertex spacing, m
  double R = 0.080, Rx = 0.100;
  double strain = -0.10, shift = 0.002;
  double bulge = 0.002;
  double amplitude = 1e-4, wavelength = 0.006, phase = 0;
  std::array<double, 3> translation{0.001, 0.002, 0.003};
};

std::array<double, 3> sheet_point(const Sheet& g, double x, double s) {
  const double t = s / g.R;
  return {x, g.R * std::sin(t), g.R * std::cos(t) - g.R - x * x / (2 * g.Rx)};
}

std::array<double, 3> sheet_normal(const Sheet& g, double x, double s) {
  const double t = s / g.R;
  std::array<double, 3> n{x * std::cos(t) / g.Rx, std::sin(t), std::cos(t)};
  const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (double& v : n) v /= l;
  return n;
}

struct Surface {
  std::vector<std::int32_t> triangles;
  std::vector<float> rest, deformed;
};

// `wrinkled` false: only the smooth motion. `facing` −1 flips the sheet upside down.
Surface make_sheet(const Sheet& g, bool wrinkled = true, double facing = 1) {
  Surface m;
  const int n = static_cast<int>(std::lround(2 * g.half / g.step)) + 1;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = -g.half + g.step * i, s = -g.half + g.step * j;
      const auto X = sheet_point(g, x, s);
      const double s2 = (1 + g.strain) * s + g.shift;
      auto p = sheet_point(g, x, s2);
      const auto nn = sheet_normal(g, x, s2);
      double lift = g.bulge * std::cos(kPi * s / 0.060);
      if (wrinkled) lift += g.amplitude * std::cos(2 * kPi * s / g.wavelength + g.phase);
      for (int k = 0; k < 3; ++k) {
        m.rest.push_back(static_cast<float>(facing * X[k]));
        m.deformed.push_back(static_cast<float>(facing * (p[k] + lift * nn[k] + g.translation[k])));
      }
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const std::int32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      m.triangles.insert(m.triangles.end(), {a, b, d, a, d, c});  // counter-clockwise from +z
    }
  }
  if (facing < 0) {  // keep the winding outward (now −z)
    for (std::size_t t = 0; t < m.triangles.size(); t += 3)
      std::swap(m.triangles[t + 1], m.triangles[t + 2]);
  }
  return m;
}

// Trough positions s (rest arc length) of the folds expected on a profile s ∈ [−half, half]:
// troughs with a crest on each side, the crests strictly inside the profile (crests at
// s = (2πk − φ) λ / 2π, troughs half a wavelength further).
std::vector<double> expected_troughs(const Sheet& g) {
  std::vector<double> crests, troughs;
  for (int k = -100; k <= 100; ++k) {
    const double c = (2 * kPi * k - g.phase) * g.wavelength / (2 * kPi);
    if (c > -g.half && c < g.half) crests.push_back(c);
  }
  for (std::size_t i = 0; i + 1 < crests.size(); ++i) {
    troughs.push_back(crests[i] + g.wavelength / 2);
  }
  return troughs;
}
std::size_t expected_folds(const Sheet& g) {
  return expected_troughs(g).size();
}

// The smooth deformed curve of profile x (the motion without the wrinkle) and its arc length
// from s = −half to s, integrated numerically (10⁴ steps): the reference for the deformed
// wavelength and the strain. Also its most compressive local stretch − 1.
struct Reference {
  double wavelength = 0, strain = 0, strain_min = 1;
};
Reference reference(const Sheet& g, double x) {
  auto smooth = [&](double s) {
    const double s2 = (1 + g.strain) * s + g.shift;
    auto p = sheet_point(g, x, s2);
    const auto n = sheet_normal(g, x, s2);
    const double lift = g.bulge * std::cos(kPi * s / 0.060);
    for (int k = 0; k < 3; ++k) p[k] += lift * n[k];
    return p;
  };
  auto stretch = [&](double s) {
    const double e = 1e-7;
    const auto a = smooth(s - e), b = smooth(s + e);
    return std::sqrt(std::pow(b[0] - a[0], 2) + std::pow(b[1] - a[1], 2) +
                     std::pow(b[2] - a[2], 2)) /
           (2 * e);
  };
  auto arc = [&](double s0, double s1) {
    const int n = 10000;
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += stretch(s0 + (s1 - s0) * (i + 0.5) / n);
    return sum * (s1 - s0) / n;
  };
  Reference r;
  const auto t = expected_troughs(g);
  r.wavelength = arc(t.front(), t.back()) / static_cast<double>(t.size() - 1);
  r.strain = arc(-g.half, g.half) / (2 * g.half) - 1;
  for (int i = 0; i <= 1000; ++i) {
    r.strain_min = std::min(r.strain_min, stretch(-g.half + 2 * g.half * i / 1000.0) - 1);
  }
  return r;
}

struct Case {
  double wavelength, amplitude, phase;
};

class WrinklesOnASheet : public ::testing::TestWithParam<Case> {};

TEST_P(WrinklesOnASheet, RecoversCountWavelengthDepthAndStrain) {
  Sheet g;
  g.wavelength = GetParam().wavelength;
  g.amplitude = GetParam().amplitude;
  g.phase = GetParam().phase;
  const auto m = make_sheet(g);
  WrinkleOptions o;  // up z, across x, 9 profiles, σ = 4 mm, δ = 0.02 mm
  const auto rep = measure_wrinkles(m.triangles, m.rest, m.deformed, o);
  const std::size_t folds = expected_folds(g);
  ASSERT_GE(folds, 5u);
  ASSERT_EQ(rep.profiles.size(), 9u);
  const double depth = 2 * g.amplitude * detrend_retention(g.wavelength, o.detrend_width);
  for (const auto& p : rep.profiles) {
    SCOPED_TRACE("profile at x = " + std::to_string(p.across));
    const auto ref = reference(g, p.across);
    const double lambda = ref.wavelength;  // deformed, ≈ (1 + ε)(1 + bulge/R) λ
    ASSERT_GT(p.samples, 100u);
    EXPECT_NEAR(p.length_rest, 2 * g.half, 0.01 * g.half);
    // Exact fold count.
    EXPECT_EQ(p.folds.size(), folds);
    // Wavelength within 2 %, spread under 5 % of it; spectral peak within 3 %.
    EXPECT_NEAR(p.wavelength_mean, lambda, 0.02 * lambda);
    EXPECT_LT(p.wavelength_std, 0.05 * lambda);
    EXPECT_NEAR(p.spectral_wavelength, lambda, 0.03 * lambda);
    // Depth within 6 % of 2A × the detrending's retention at the rest wavelength (linear
    // interpolation between vertices 0.4 mm apart flattens a crest by up to A(πΔ/λ)²/2: 4 % at
    // λ = 4 mm).
    EXPECT_NEAR(p.depth_mean, depth, 0.06 * depth);
    EXPECT_LT(p.depth_max, 1.06 * depth);
    // The smooth motion's strain (the smoothing of a circle of radius 80 mm over σ = 4 mm changes
    // lengths by < 0.1 %).
    EXPECT_NEAR(p.strain, ref.strain, 0.002);
    EXPECT_NEAR(p.strain_min, ref.strain_min, 0.005);
  }
  EXPECT_EQ(rep.summary.folds, 9 * folds);
  const double lambda = reference(g, 0).wavelength;
  EXPECT_NEAR(rep.summary.wavelength_mean, lambda, 0.02 * lambda);
  EXPECT_NEAR(rep.summary.depth_mean, depth, 0.06 * depth);
  EXPECT_NEAR(rep.summary.retention, detrend_retention(g.wavelength, o.detrend_width), 0.01);
}

INSTANTIATE_TEST_SUITE_P(
    Wrinkles, WrinklesOnASheet,
    ::testing::Values(Case{0.006, 1e-4, 0.3}, Case{0.008, 5e-5, 2.0}, Case{0.004, 3e-5, -1.0}),
    [](const auto& info) {
      return "lambda_" +
             std::to_string(static_cast<int>(std::lround(info.param.wavelength * 1e3))) + "mm";
    });

TEST(Wrinkles, SmoothMotionAndRestHaveNoFolds) {
  Sheet g;
  const auto m = make_sheet(g, /*wrinkled=*/false);
  WrinkleOptions o;
  const auto smooth = measure_wrinkles(m.triangles, m.rest, m.deformed, o);
  EXPECT_EQ(smooth.summary.folds, 0u);
  // What leaks of the bulge (Λ = 120 mm: 1 − H = 2e−4) and the slide along the circle stays far
  // below the threshold.
  EXPECT_LT(smooth.summary.rms, 0.1 * o.min_depth);
  EXPECT_NEAR(smooth.summary.strain, reference(g, 0).strain, 0.002);
  const auto rest = measure_wrinkles(m.triangles, m.rest, m.rest, o);
  EXPECT_EQ(rest.summary.folds, 0u);
  EXPECT_EQ(rest.summary.rms, 0.0);
  EXPECT_NEAR(rest.summary.strain, 0.0, 1e-9);
}

TEST(Wrinkles, FoldsShallowerThanTheThresholdAreNotCounted) {
  Sheet g;
  g.amplitude = 0.8e-5;  // depth 0.016 mm < δ = 0.02 mm
  auto m = make_sheet(g);
  WrinkleOptions o;
  auto rep = measure_wrinkles(m.triangles, m.rest, m.deformed, o);
  EXPECT_EQ(rep.summary.folds, 0u);
  // The spectrum still sees the wave.
  const double lambda = reference(g, 0).wavelength;
  EXPECT_NEAR(rep.summary.spectral_wavelength, lambda, 0.03 * lambda);
  o.min_depth = 1e-5;  // 0.01 mm: now they count
  rep = measure_wrinkles(m.triangles, m.rest, m.deformed, o);
  EXPECT_EQ(rep.summary.folds, 9 * expected_folds(g));
}

// A plane rising along y with slope 0.3 (up z), lifted along its normal by A cos(2π q) where
// q = z / h (locked to voxel layers of size h: troughs at phase ½) or q = s / λ (not locked).
Surface make_slope(double h, double wavelength, bool locked) {
  Surface m;
  const double half = 0.030, step = 0.0004, slope = 0.3, A = 5e-5;
  const double c = 1 / std::sqrt(1 + slope * slope);
  const int n = static_cast<int>(std::lround(2 * half / step)) + 1;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double x = -half + step * i, y = -half + step * j, z = slope * y;
      const double q = locked ? z / h : y / c / wavelength;
      const double w = A * std::cos(2 * kPi * q);
      const double X[3] = {x, y, z}, N[3] = {0, -slope * c, c};
      for (int k = 0; k < 3; ++k) {
        m.rest.push_back(static_cast<float>(X[k]));
        m.deformed.push_back(static_cast<float>(X[k] + w * N[k]));
      }
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      const std::int32_t a = j * n + i, b = a + 1, cc = a + n, d = cc + 1;
      m.triangles.insert(m.triangles.end(), {a, b, d, a, d, cc});
    }
  }
  return m;
}

TEST(Wrinkles, FoldsLockedToVoxelLayersAreFlagged) {
  // Layers h = 1.5 mm crossed every h / 0.3 = 5 mm along y: a locked imprint has R ≈ 1; a wave of
  // 6.85 mm (the phase advances 0.41 of a layer per fold) has R well below.
  WrinkleOptions o;
  o.voxel_size = 0.0015;
  o.lattice_origin = {0.0003, 0.0007, 0.0002};
  const auto locked = make_slope(o.voxel_size, 0, true);
  const auto a = measure_wrinkles(locked.triangles, locked.rest, locked.deformed, o);
  ASSERT_GT(a.summary.folds, 40u);
  EXPECT_GT(a.summary.layer_locking, 0.95);
  EXPECT_GT(a.summary.layers_spanned, 8.0);
  // Layer period h / slope along the arc: slope dz/ds = 0.3 / √1.09.
  const double period = o.voxel_size * std::sqrt(1.09) / 0.3;
  EXPECT_NEAR(a.summary.layer_period, period, 0.01 * period);
  EXPECT_NEAR(a.summary.wavelength_mean, period, 0.02 * period);
  for (const auto& f : a.profiles[4].folds) {
    // Troughs where cos(2π z/h) = −1: z/h = ½ mod 1, i.e. φ = frac(½ − o_z/h).
    const double expect = 0.5 - 0.0002 / 0.0015 + 1;
    EXPECT_NEAR(f.layer_phase, expect - std::floor(expect), 0.03);
  }
  const auto free = make_slope(o.voxel_size, 0.00685, false);
  const auto b = measure_wrinkles(free.triangles, free.rest, free.deformed, o);
  ASSERT_GT(b.summary.folds, 30u);
  EXPECT_LT(b.summary.layer_locking, 0.3);
  o.voxel_size = 0;  // unknown lattice: no phases
  const auto c = measure_wrinkles(free.triangles, free.rest, free.deformed, o);
  EXPECT_TRUE(std::isnan(c.summary.layer_locking));
}

TEST(Wrinkles, DetrendingFollowsItsTransferFunction) {
  // A pure sine of wavelength λ on a straight line: the interior residual amplitude is
  // retention(λ) = 1 − (1 + x) e^(−x), x = (2πσ/λ)²/2, within 1 %; quadratics pass exactly.
  const double sigma = 1.0;
  std::vector<double> t, v, q;
  for (int i = 0; i <= 4000; ++i) {
    t.push_back(0.01 * i);
    q.push_back(3 - 2 * t.back() + 0.25 * t.back() * t.back());
  }
  const auto qs = local_quadratic_smooth(t, q, 1, sigma);
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(qs[i], q[i], 1e-9 * (1 + std::abs(q[i])));
  for (double lambda : {2.0, 3.43, 5.0}) {
    v.clear();
    for (double ti : t) v.push_back(std::sin(2 * kPi * ti / lambda));
    const auto sm = local_quadratic_smooth(t, v, 1, sigma);
    double amp = 0;
    for (std::size_t i = 1000; i < 3000; ++i) amp = std::max(amp, std::abs(v[i] - sm[i]));
    EXPECT_NEAR(amp, detrend_retention(lambda, sigma), 0.01) << "lambda " << lambda;
  }
  EXPECT_NEAR(detrend_retention(2.25, 1.0), 0.90, 0.01);
  EXPECT_NEAR(detrend_retention(3.43, 1.0), 0.50, 0.01);
  EXPECT_NEAR(detrend_retention(6.09, 1.0), 0.10, 0.01);
}

// Expects `f` to throw E whose message contains every piece.
template <typename E, typename F>
void expect_error(F&& f, std::vector<std::string> pieces) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const E& e) {
    for (const auto& p : pieces) {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << " lacks " << p;
    }
  }
}

TEST(Wrinkles, BadInputIsRejectedWithClearErrors) {
  Sheet g;
  g.step = 0.002;
  const auto m = make_sheet(g);
  WrinkleOptions o;
  auto short_frame = m.deformed;
  short_frame.resize(short_frame.size() - 3);
  expect_error<sinew::FormatError>(
      [&] { measure_wrinkles(m.triangles, m.rest, short_frame, o, "r.h5"); },
      {"r.h5", "positions", "rest pose"});
  auto bad_ids = m.triangles;
  bad_ids[3 * 7 + 1] = 1 << 20;
  expect_error<sinew::FormatError>(
      [&] { measure_wrinkles(bad_ids, m.rest, m.deformed, o, "r.h5"); },
      {"r.h5", "triangles[7]", "out of range"});
  auto nan = m.deformed;
  nan[3 * 11 + 2] = std::nanf("");
  expect_error<sinew::FormatError>([&] { measure_wrinkles(m.triangles, m.rest, nan, o, "r.h5"); },
                                   {"positions[11]", "non-finite"});
  auto same = o;
  same.across = same.up;
  expect_error<sinew::ConfigError>([&] { measure_wrinkles(m.triangles, m.rest, m.deformed, same); },
                                   {"across", "differ"});
  auto depth = o;
  depth.min_depth = 0;
  expect_error<sinew::ConfigError>(
      [&] { measure_wrinkles(m.triangles, m.rest, m.deformed, depth); }, {"min_depth"});
  auto none = o;
  none.profiles = 0;
  expect_error<sinew::ConfigError>([&] { measure_wrinkles(m.triangles, m.rest, m.deformed, none); },
                                   {"profiles"});
  auto away = o;
  away.region = std::array<double, 6>{1, 2, 1, 2, 1, 2};  // nowhere near the sheet
  expect_error<sinew::GeometryError>(
      [&] { measure_wrinkles(m.triangles, m.rest, m.deformed, away); }, {"inside the region"});
  const auto down = make_sheet(g, true, -1);  // facing −z
  expect_error<sinew::GeometryError>(
      [&] { measure_wrinkles(down.triangles, down.rest, down.deformed, o, "down.h5"); },
      {"down.h5", "no triangle faces +z"});
  SurfaceAnimation a;
  a.file = "a.h5";
  a.triangles = m.triangles;
  a.rest = m.rest;
  a.frames = {m.rest};
  a.times = {0};
  expect_error<sinew::ConfigError>([&] { measure_wrinkles(a, 3, o); }, {"a.h5", "frame 3"});
  expect_error<sinew::ConfigError>([&] { parse_axis("w", "--up"); }, {"--up", "\"w\""});
}

#ifdef SINEW_WRINKLES_EXE
// A results file as docs/results-format.md describes it: frame 0 the rest pose, frame 1 the
// wrinkled sheet (one dummy volume element of edge 1 mm, for the voxel size).
void write_results(const std::string& path, const Surface& m) {
  auto f = h5::create_file(path);
  h5::set_attribute(f, "format", std::string(sinew::simulator::kResultsFormatName), path);
  h5::set_attribute(f, "format_version", std::int64_t{sinew::simulator::kResultsFormatVersion},
                    path);
  h5::create_group(f, "/mesh", path);
  h5::create_group(f, "/frames", path);
  h5::create_group(f, "/surfaces", path);
  h5::create_group(f, "/surfaces/skin", path);
  std::vector<double> rest(24);
  for (int i = 0; i < 8; ++i) {
    rest[3 * i] = i & 1 ? 0.001 : 0;
    rest[3 * i + 1] = i & 2 ? 0.001 : 0;
    rest[3 * i + 2] = i & 4 ? 0.001 : 0;
  }
  h5::write(f, "/mesh/rest_positions", {8, 3}, rest.data(), path);
  const std::vector<std::int32_t> conn = {0, 1, 3, 2, 4, 5, 7, 6}, mat = {0};
  h5::write(f, "/mesh/connectivity", {1, 8}, conn.data(), path);
  h5::write(f, "/mesh/material", {1}, mat.data(), path);
  const std::vector<double> times = {0, 0.05};
  const std::vector<std::int64_t> steps = {0, 500};
  h5::write(f, "/frames/time", {2}, times.data(), path);
  h5::write(f, "/frames/step", {2}, steps.data(), path);
  std::vector<double> disp(48, 0.0);
  h5::write(f, "/frames/displacement", {2, 8, 3}, disp.data(), path);
  std::vector<double> pos(m.rest.begin(), m.rest.end());
  pos.insert(pos.end(), m.deformed.begin(), m.deformed.end());
  const hsize_t nv = m.rest.size() / 3, nt = m.triangles.size() / 3;
  h5::write(f, "/surfaces/skin/positions", {2, nv, 3}, pos.data(), path);
  h5::write(f, "/surfaces/skin/triangles", {nt, 3}, m.triangles.data(), path);
}

TEST(WrinklesTool, MeasuresAResultsFile) {
  const auto dir = fs::temp_directory_path() / ("sinew_wrinkles_test_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  Sheet g;
  g.step = 0.0005;
  g.phase = 0.3;
  const auto m = make_sheet(g);
  const auto results = (dir / "results.h5").string();
  write_results(results, m);
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string(SINEW_WRINKLES_EXE) + " " + results + " " + args + " > " +
                            (dir / "log.txt").string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };
  auto log = [&] {
    std::ifstream in(dir / "log.txt");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  ASSERT_EQ(run("--time 0.04 --profiles 5 --csv " + (dir / "w.csv").string() + " --json " +
                (dir / "w.json").string() + " --trace " + (dir / "t.csv").string()),
            0)
      << log();
  EXPECT_NE(log().find("frame 1 of 2"), std::string::npos) << log();
  EXPECT_NE(log().find("voxel size 1.000 mm"), std::string::npos) << log();
  std::ifstream csv(dir / "w.csv");
  std::string line, last;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("profile,across_mm,samples,", 0), 0u);
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    last = line;
  }
  EXPECT_EQ(rows, 6);
  EXPECT_EQ(last.rfind("all,", 0), 0u) << last;
  std::ifstream js(dir / "w.json");
  const auto j = nlohmann::json::parse(js);
  const auto folds = expected_folds(g);
  EXPECT_EQ(j["summary"]["folds"].get<std::size_t>(), 5 * folds);
  const double lambda = 1e3 * reference(g, 0).wavelength;
  EXPECT_NEAR(j["summary"]["wavelength_mean_mm"].get<double>(), lambda, 0.02 * lambda);
  EXPECT_NEAR(j["summary"]["depth_mean_mm"].get<double>(), 0.2, 0.06 * 0.2);
  EXPECT_EQ(j["profiles"][0]["fold_list"].size(), folds);
  EXPECT_TRUE(fs::file_size(dir / "t.csv") > 1000);
  // The rest frame: no folds.
  ASSERT_EQ(run("--frame 0 --json " + (dir / "r.json").string()), 0) << log();
  std::ifstream rs(dir / "r.json");
  EXPECT_EQ(nlohmann::json::parse(rs)["summary"]["folds"].get<int>(), 0);
  // Mistakes.
  EXPECT_EQ(run("--frame 2"), 2);
  EXPECT_NE(log().find("frame 2 out of range"), std::string::npos) << log();
  EXPECT_EQ(run("--up x --across x"), 2);
  EXPECT_EQ(run("--region 1,2,3"), 2);
  EXPECT_NE(log().find("--region"), std::string::npos) << log();
  EXPECT_EQ(run("--surface brow"), 1);
  EXPECT_NE(log().find("brow"), std::string::npos) << log();
  fs::remove_all(dir);
}
#endif

}  // namespace
