// The expressions on the sample head's rig (data/scenes/face_*.yaml, docs/faces.md), on the CPU
// at the CI's coarse resolution (data/specs/sample_head_4mm.yaml) and on the CUDA backend when a
// device is there (skipping visibly otherwise): each runs to its end with no inversion; the
// mirror-symmetric ones give mirror-symmetric skin displacements to 1% of the largest; the smile
// lifts the mouth's corners and draws them back by millimetres, the brow raise lifts the brows,
// the frown draws the inner brows together, the one-sided sneer lifts the left side only.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "pipeline_test_util.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/simulator/engine/cuda_backend.hpp"
#include "sinew/simulator/run/runner.hpp"
#include "sinew/voxelizer/head.hpp"
#include "sinew/voxelizer/landmarks.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"

namespace sinew::voxelizer {
namespace {

const std::filesystem::path kSource = SINEW_SOURCE_DIR;

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The layout of the repository's data/ folder in a temporary one: the generated head in
// meshes/head, the committed landmarks, the CI spec voxelized to specs/sample_head_4mm.h5.
const testing::TempDir& workspace() {
  static const testing::TempDir dir = [] {
    testing::TempDir d;
    write_head(HeadParams{}, d / "meshes/head");
    std::filesystem::create_directories(d / "landmarks");
    std::filesystem::copy_file(kSource / "data/landmarks/sample_head.yaml",
                               d / "landmarks/sample_head.yaml");
    std::filesystem::create_directories(d / "specs");
    const auto spec_path = d / "specs/sample_head_4mm.yaml";
    std::filesystem::copy_file(kSource / "data/specs/sample_head_4mm.yaml", spec_path);
    const Spec spec = read_spec(spec_path);
    formats::write_model(voxelize(spec).model, (d / "specs/sample_head_4mm.h5").string());
    std::filesystem::create_directories(d / "scenes");
    return d;
  }();
  return dir;
}

struct ExpressionRun {
  simulator::RunSummary summary;
  std::filesystem::path dir;
};

// The scan in ../shared, or where the environment's SINEW_SHARED_MESH_DIR says.
const std::filesystem::path kScan = testing::shared_mesh_dir() / "lee_perry_smith_head.obj";

// The Lee Perry-Smith scan's model (data/specs/lee_perry_smith_4mm.yaml with the mesh path pointed
// at kScan), voxelized into the workspace once.
// A committed scan spec (data/specs/SOURCE.yaml) with the mesh path pointed at kScan and `edit`
// (text to text) applied, voxelized into the workspace as specs/NAME.h5; returns the model.
formats::Model voxelize_scan_spec(const std::string& source, const std::string& name,
                                  const std::function<void(std::string&)>& edit = {}) {
  const auto& d = workspace();
  if (!std::filesystem::exists(d / "landmarks/lee_perry_smith.yaml"))
    std::filesystem::copy_file(kSource / "data/landmarks/lee_perry_smith.yaml",
                               d / "landmarks/lee_perry_smith.yaml");
  std::string spec = read(kSource / ("data/specs/" + source + ".yaml"));
  const std::string rel = "../../../shared/data/meshes/lee_perry_smith_head.obj";
  const auto at = spec.find(rel);
  EXPECT_NE(at, std::string::npos) << source;
  if (at != std::string::npos) spec.replace(at, rel.size(), kScan.string());
  if (edit) edit(spec);
  const auto path = d.write("specs/" + name + ".yaml", spec);
  formats::Model m = voxelize(read_spec(path)).model;
  formats::write_model(m, (d / ("specs/" + name + ".h5")).string());
  return m;
}

void voxelize_scan() {
  static bool done = false;
  if (done) return;
  voxelize_scan_spec("lee_perry_smith_4mm", "lee_perry_smith_4mm");
  done = true;
}

// Runs data/scenes/face_NAME.yaml on `model` (sample_head_4mm or lee_perry_smith_4mm) on
// `device` (without `contact`: the lips free to pass through each other), once per set.
const ExpressionRun& run(const std::string& name, const std::string& device,
                         const std::string& model = "sample_head_4mm", bool contact = true) {
  static std::map<std::tuple<std::string, std::string, std::string, bool>, ExpressionRun> runs;
  const auto key = std::make_tuple(name, device, model, contact);
  if (auto it = runs.find(key); it != runs.end()) return it->second;
  const auto& d = workspace();
  std::string scene = read(kSource / ("data/scenes/face_" + name + ".yaml"));
  const std::string original = "model: ../specs/sample_head_3mm.h5";
  const auto at = scene.find(original);
  EXPECT_NE(at, std::string::npos);
  scene.replace(at, original.size(), "model: ../specs/" + model + ".h5");
  // The scenes hold their peak for the tissue to come to rest (0.5 s, the jaw's poses 0.6 s:
  // docs/faces.md); the muscles' checks here (direction, symmetry, no inversion) hold from the end
  // of the ramp, so CI stops them at 0.1 s. The tissue follows the jaw more slowly (the chin and
  // lips are carried by the whole lower face): those poses run to 0.4 s, and the chewing stroke
  // (the tissue's own inertia, 6 times the steps) to its widest point, 0.12 s.
  const std::map<std::string, std::string> cut = {
      {"ah", "0.4"}, {"surprise", "0.4"}, {"oo", "0.4"}, {"chew", "0.12"}};
  const std::string held = "\nduration: ";
  const auto h = scene.find(held);
  EXPECT_NE(h, std::string::npos);
  if (h != std::string::npos) {
    const auto end = scene.find('\n', h + 1);
    scene.replace(h, end - h, held + (cut.count(name) ? cut.at(name) : "0.1"));
  }
  // The scenes let the sample head's forehead glide (its spec's sliding condition) and its lips
  // touch (the pairs across its jaw's cut); a model without them (the scan's spec holds its deep
  // tissue and has no jaw) runs them without `sliding` and `contact`.
  if (model.rfind("sample_head", 0) != 0) {
    const std::string glide = ", sliding, contact]";
    const auto g = scene.find(glide);
    EXPECT_NE(g, std::string::npos);
    if (g != std::string::npos) scene.replace(g, glide.size(), "]");
  }
  if (!contact) {
    const std::string touch = ", contact]";
    const auto g = scene.find(touch);
    EXPECT_NE(g, std::string::npos);
    if (g != std::string::npos) scene.replace(g, touch.size(), "]");
  }
  const std::string tag = name + "_" + device + "_" + model + (contact ? "" : "_no_contact");
  const auto scene_path = d.write("scenes/" + tag + ".yaml", scene);
  simulator::RunOptions o;
  o.scene_path = scene_path.string();
  o.output_dir = (d / ("out_" + tag)).string();
  o.device = device;
  o.quiet = true;
  o.print = [](const std::string&) {};
  ExpressionRun r{simulator::run_scene(o).summary, o.output_dir};
  return runs.emplace(key, std::move(r)).first->second;
}

// The last row of a displacement probe: (ux, uy, uz) in mm.
Vec3d probe_mm(const ExpressionRun& r, const std::string& probe) {
  std::ifstream in(r.dir / ("probe_" + probe + ".csv"));
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty()) last = line;
  std::stringstream s(last);
  std::string cell;
  std::vector<double> v;
  while (std::getline(s, cell, ',')) v.push_back(std::stod(cell));
  EXPECT_EQ(v.size(), 5u) << probe;
  return v.size() == 5 ? Vec3d{1e3 * v[2], 1e3 * v[3], 1e3 * v[4]} : Vec3d{0, 0, 0};
}

// max over skin vertices v with a mirror image m(v) of |u(v) − M u(m(v))|, and max |u|, at the
// last frame; M mirrors x. The skin mesh is its own mirror image to the micrometre.
std::pair<double, double> mirror_error(const ExpressionRun& r) {
  const auto s = postprocess::read_surface((r.dir / "results.h5").string(), "skin");
  const std::size_t n = s.vertex_count();
  const auto& last = s.frames.back();
  std::map<std::tuple<long, long, long>, std::size_t> index;
  auto key = [&](std::size_t v, bool mirror) {
    return std::make_tuple(std::lround((mirror ? -1 : 1) * s.rest[3 * v] * 1e6),
                           std::lround(s.rest[3 * v + 1] * 1e6),
                           std::lround(s.rest[3 * v + 2] * 1e6));
  };
  for (std::size_t v = 0; v < n; ++v) index[key(v, false)] = v;
  double err = 0, umax = 0;
  std::size_t paired = 0;
  for (std::size_t v = 0; v < n; ++v) {
    const Vec3d u{last[3 * v] - s.rest[3 * v], last[3 * v + 1] - s.rest[3 * v + 1],
                  last[3 * v + 2] - s.rest[3 * v + 2]};
    umax = std::max(umax, norm(u));
    const auto it = index.find(key(v, true));
    if (it == index.end()) continue;
    const std::size_t w = it->second;
    ++paired;
    const Vec3d uw{-(last[3 * w] - s.rest[3 * w]), last[3 * w + 1] - s.rest[3 * w + 1],
                   last[3 * w + 2] - s.rest[3 * w + 2]};
    err = std::max(err, norm(u - uw));
  }
  EXPECT_GT(paired, n * 9 / 10);  // all but the back's seam column
  return {err, umax};
}

// The skin's displacement at the last frame at its vertex nearest `point` (the scenes' probes are
// the sample head's points; on the scan the landmarks say where), m.
Vec3d skin_displacement(const ExpressionRun& r, const Vec3d& point) {
  const auto s = postprocess::read_surface((r.dir / "results.h5").string(), "skin");
  std::size_t best = 0;
  double d_best = 1e30;
  for (std::size_t v = 0; v < s.vertex_count(); ++v) {
    const Vec3d p{s.rest[3 * v], s.rest[3 * v + 1], s.rest[3 * v + 2]};
    if (norm(p - point) < d_best) d_best = norm(p - point), best = v;
  }
  const auto& last = s.frames.back();
  return {last[3 * best] - s.rest[3 * best], last[3 * best + 1] - s.rest[3 * best + 1],
          last[3 * best + 2] - s.rest[3 * best + 2]};
}

// The C-line (Cotofana et al., Plast Reconstr Surg: in a maximal brow raise the lower forehead
// moves up and the upper forehead down, meeting at 60.9 ± 10.2% (men), 60.6 ± 9.6% (women) of the
// forehead's height): up the skin over the left frontalis's middle (the frontmost skin vertices
// within 2.5 mm of the left brow's centre across, in 3 mm bands of height from the brow to 15 mm
// above the hairline; y is up, z forward on both heads), where the bands' mean rise at the last
// frame turns into a descent, as a share of the height from the brow to the hairline. NaN when it
// does not turn.
double c_line_share(const ExpressionRun& r, const Vec3d& brow, const Vec3d& hairline) {
  const auto s = postprocess::read_surface((r.dir / "results.h5").string(), "skin");
  const auto& last = s.frames.back();
  const double band = 3e-3, top = hairline[1] + 15e-3;
  const int bands = static_cast<int>(std::ceil((top - brow[1]) / band));
  std::vector<double> front(static_cast<std::size_t>(bands), -1e9);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<double> sum(front.size(), 0), count(front.size(), 0);
    for (std::size_t v = 0; v < s.vertex_count(); ++v) {
      const double x = s.rest[3 * v], y = s.rest[3 * v + 1], z = s.rest[3 * v + 2];
      if (std::abs(x - brow[0]) > 2.5e-3 || y < brow[1] || y >= top) continue;
      const auto b = static_cast<std::size_t>((y - brow[1]) / band);
      if (pass == 0) {
        front[b] = std::max(front[b], z);
      } else if (z > front[b] - band) {  // the forehead's skin, not the back of the head
        sum[b] += last[3 * v + 1] - s.rest[3 * v + 1];
        count[b] += 1;
      }
    }
    if (pass == 0) continue;
    double prev_y = 0, prev_u = 0;
    bool have = false;
    for (std::size_t b = 0; b < front.size(); ++b) {
      if (count[b] == 0) continue;
      const double y = brow[1] + (b + 0.5) * band, u = sum[b] / count[b];
      if (have && prev_u > 0 && u <= 0) {
        const double cross = prev_y + (y - prev_y) * prev_u / (prev_u - u);
        return (cross - brow[1]) / (hairline[1] - brow[1]);
      }
      prev_y = y, prev_u = u, have = true;
    }
  }
  return std::nan("");
}

// Expected motion per expression, in mm (x the subject's left, y up, z forward out of the face).
void expect_motion(const std::string& name, const ExpressionRun& r) {
  auto u = [&](const char* probe) { return probe_mm(r, probe); };
  if (name == "smile") {
    // The mouth's corners go up by millimetres, back and outward.
    for (const char* p : {"mouth_corner_left", "mouth_corner_right"}) {
      SCOPED_TRACE(p);
      EXPECT_GT(u(p).y, 2.0);
      EXPECT_LT(u(p).z, -0.5);
    }
    EXPECT_GT(u("mouth_corner_left").x, 0.2);
    EXPECT_LT(u("mouth_corner_right").x, -0.2);
  } else if (name == "brow_raise") {
    EXPECT_GT(u("brow_centre_left").y, 1.5);
    EXPECT_GT(u("brow_centre_right").y, 1.5);
    EXPECT_LT(std::abs(u("mouth_corner_left").y), 0.1);  // the mouth stays
    // Up the frontalis's middle the forehead rises, less towards the top: the frontalis reaches
    // into the galea's anchor (the spec's held scalp, y > 75 mm) 12 mm above the hairline's
    // height, and the sample head's forehead (32.5 mm from the brow to the hairline, about half an
    // adult's) is too short for the upper part to come down as well (the C-line: checked on the
    // scan, below; docs/faces.md).
    for (const char* p : {"forehead_31", "forehead_39", "forehead_46", "forehead_50"}) {
      SCOPED_TRACE(p);
      EXPECT_GT(u(p).y, 0.5 * u("brow_centre_left").y);
    }
    EXPECT_LT(u("forehead_68").y, 0.5 * u("brow_centre_left").y);
  } else if (name == "frown") {
    // The inner brows move towards the midline.
    EXPECT_LT(u("brow_inner_left").x, -0.5);
    EXPECT_GT(u("brow_inner_right").x, 0.5);
  } else if (name == "sneer") {
    EXPECT_GT(u("alar_base_left").y, 2.0);
    EXPECT_LT(std::abs(u("alar_base_right").y), 0.2);  // one-sided
  } else if (name == "pout") {
    EXPECT_GT(u("upper_lip").z, 1.0);           // the lips come forward
    EXPECT_LT(u("mouth_corner_left").x, -1.0);  // the sphincter narrows the mouth
    EXPECT_GT(u("mouth_corner_right").x, 1.0);
  } else if (name == "ah" || name == "surprise") {
    // The jaw turned 7° (ah) or 10° (surprise) about the axis 12 mm in front of the tragi: the
    // incisal point moves 7.5 (10.7) mm down and 9.5 (13.4) back, and the lower lip and chin
    // follow it down and back; the upper lip stays (the lips part at the cut between them). At
    // 4 mm at 0.4 s, with the paper's 48 MPa stratum corneum: lower lip (0.1, −5.2, −8.7), chin
    // (−0.1, −4.4, −8.9), lips parted 4.6 mm (ah); (0.1, −6.4, −12.4), (−0.1, −5.9, −12.3),
    // 6.0 mm (surprise).
    const bool ah = name == "ah";
    EXPECT_LT(u("lower_lip").y, ah ? -3.5 : -4.5);
    EXPECT_LT(u("chin").y, ah ? -3.0 : -4.0);
    EXPECT_LT(u("chin").z, ah ? -6.0 : -9.0);
    EXPECT_LT(std::abs(u("upper_lip").y), 1.5);
    EXPECT_GT(u("upper_lip").y - u("lower_lip").y, ah ? 3.0 : 4.0);  // the lips part
    if (!ah) {
      EXPECT_GT(u("brow_centre_left").y, 2.0);
    }
  } else if (name == "oo") {
    // The pout with the jaw 3° open: upper lip (0.8, −1.7, 2.9), lower lip (0.7, −3.8, −1.4).
    EXPECT_GT(u("upper_lip").z, 1.5);           // the lips forward, as the pout
    EXPECT_LT(u("lower_lip").y, -2.5);          // with the jaw slightly open
    EXPECT_LT(u("mouth_corner_left").x, -1.0);  // the sphincter narrows the mouth
  } else if (name == "chew") {
    // At its widest (0.12 s) the stroke is 8° open and 3 mm to the subject's left: the chin at
    // (2.6, −4.9, −10.3) mm.
    EXPECT_GT(u("chin").x, 1.5);
    EXPECT_LT(u("chin").y, -3.0);
    EXPECT_LT(u("chin").z, -6.0);
  } else if (name == "grimace") {
    EXPECT_LT(u("brow_inner_left").x, -0.5);  // the frown in it
    // The corners drawn back (0.48 mm at 4 mm, 0.6 at 3 mm; 0.5 and 0.7 before the depressors'
    // self-intersecting sheets were filled by the winding number, docs/voxelizer.md).
    EXPECT_LT(u("mouth_corner_left").z, -0.3);
  }
}

// The sample head's jaw (rig.jaw, data/specs/sample_head_4mm.yaml): the mandible cut from the
// skull below the lips, hinged 12 mm in front of the tragi, the lips cut apart.
TEST(SampleHeadJaw, TheMandibleIsCutFromTheSkullAlongTheLandmarksPlanes) {
  const auto m = formats::read_model((workspace() / "specs/sample_head_4mm.h5").string());
  ASSERT_TRUE(m.jaw);
  const auto& j = *m.jaw;
  // Tragi (±74.773, 3.490, 6.623) mm: the pivot between them, 12 mm along the face's forward
  // (0, −0.0391, 0.9992), at (0, 3.020, 18.614) mm; the axis to the subject's left.
  EXPECT_NEAR(j.pivot[0], 0, 1e-9);
  EXPECT_NEAR(j.pivot[1], 3.020e-3, 1e-6);
  EXPECT_NEAR(j.pivot[2], 18.614e-3, 1e-6);
  EXPECT_NEAR(j.axis[0], 1, 1e-9);
  EXPECT_NEAR(j.forward[2], 0.99923, 1e-5);
  // The incisal point 12 mm behind the stomion (0, −71.386, 96.465) mm: (0, −70.916, 84.474).
  EXPECT_NEAR(j.incisal[1], -70.916e-3, 1e-6);
  EXPECT_NEAR(j.incisal[2], 84.474e-3, 1e-6);
  EXPECT_GT(j.nodes.size(), 200u);
  // Every jaw node lies below the occlusal plane (through the stomion, normal to the face's up =
  // forward × axis) and at most 10 mm behind the joint along forward; none is rigid.
  const Vec3d f{j.forward[0], j.forward[1], j.forward[2]}, a{j.axis[0], j.axis[1], j.axis[2]};
  const Vec3d up = cross(f, a), stomion{0, -71.386e-3, 96.465e-3};
  const Vec3d pivot{j.pivot[0], j.pivot[1], j.pivot[2]};
  for (const auto nd : j.nodes) {
    const auto q = m.node_position(nd);
    const Vec3d p{q[0], q[1], q[2]};
    EXPECT_LT(dot(p - stomion, up), 0.0) << nd;
    EXPECT_GT(dot(p - pivot, f), -10e-3 - 1e-9) << nd;
    EXPECT_FALSE(std::binary_search(m.rigid_nodes.begin(), m.rigid_nodes.end(), nd)) << nd;
  }
}

class FaceExpression : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

// Each expression on each backend: runs to its end with no inversion (an inversion stops the run
// with InstabilityError), moves as expected, and, when its activations are mirror-symmetric, gives
// mirror-symmetric skin displacements to 1% of the largest. One case per run (ctest starts each
// case in its own process).
TEST_P(FaceExpression, RunsWithoutInversionAndMovesAsExpected) {
  const auto& [name, device] = GetParam();
  if (device == "cuda" && !simulator::cuda_device_available()) GTEST_SKIP() << "no CUDA device";
  const ExpressionRun& r = run(name, device);
  EXPECT_EQ(r.summary.status, "completed");
  EXPECT_EQ(r.summary.steps_done, r.summary.steps_planned);
  expect_motion(name, r);
  if (r.summary.jaw_nodes > 0) {
    // The incisal point turns about the axis 99.02 mm away: chord 2 r sin(θ/2).
    const std::map<std::string, double> opening_mm = {
        {"ah", 12.090}, {"surprise", 17.260}, {"oo", 5.184}};
    if (const auto it = opening_mm.find(name); it != opening_mm.end()) {
      EXPECT_NEAR(1e3 * r.summary.jaw_max_incisal_opening, it->second, 0.005);
    }
  }
  if (name != "sneer" && name != "chew") {  // the sneer and the chewing stroke are one-sided
    const auto [err, umax] = mirror_error(r);
    EXPECT_GT(umax, 1e-4);  // it moved (> 0.1 mm)
    EXPECT_LE(err, 0.01 * umax) << "largest displacement " << umax * 1e3 << " mm";
  }
}

std::string name_of(const ::testing::TestParamInfo<std::tuple<std::string, std::string>>& i) {
  return std::get<0>(i.param) + "_" + std::get<1>(i.param);
}

INSTANTIATE_TEST_SUITE_P(SampleHead, FaceExpression,
                         ::testing::Combine(::testing::Values("brow_raise", "frown", "smile",
                                                              "sneer", "pout", "grimace", "ah",
                                                              "surprise", "oo", "chew"),
                                            ::testing::Values("cpu", "cuda")),
                         name_of);

// The smallest gap across the lips' pairs (formats::Jaw::lip_pairs) over every frame of a run, mm:
// (x_upper − x_lower) · up with x = rest + u and up = forward × axis; negative where a lip has
// passed through the other. At rest it is the cut's height, one voxel (4 mm).
double min_lip_gap_mm(const ExpressionRun& r) {
  const formats::Model m = formats::read_model((workspace() / "specs/sample_head_4mm.h5").string());
  EXPECT_TRUE(m.jaw && !m.jaw->lip_pairs.empty());
  if (!m.jaw) return 0;
  const auto& j = *m.jaw;
  const Vec3d f{j.forward[0], j.forward[1], j.forward[2]}, a{j.axis[0], j.axis[1], j.axis[2]};
  const Vec3d up = cross(f, a);
  const std::string path = (r.dir / "results.h5").string();
  const auto file = formats::hdf5::open_checked(path);
  const auto u = formats::hdf5::read<double>(file, "/frames/displacement", path);
  const std::size_t n = m.node_count(), frames = u.size() / (3 * n);
  EXPECT_GT(frames, 1u);
  double gap = 1e9;
  for (std::size_t fr = 0; fr < frames; ++fr) {
    const double* uf = u.data() + 3 * n * fr;
    for (const auto& [upper, lower] : j.lip_pairs) {
      const auto pu = m.node_position(upper), pl = m.node_position(lower);
      double g = 0;
      for (int k = 0; k < 3; ++k)
        g += (pu[std::size_t(k)] + uf[3 * std::size_t(upper) + std::size_t(k)] -
              pl[std::size_t(k)] - uf[3 * std::size_t(lower) + std::size_t(k)]) *
             up[k];
      gap = std::min(gap, g);
    }
  }
  return 1e3 * gap;
}

class LipContact : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

// The lips touch instead of passing through each other (`contact`, physics/lip_contact.hpp): in
// the pout, the smile, "oo" and the chewing stroke no lower-lip node rises above its upper-lip
// partner at any frame, on each backend, and the run reports that gap itself. The pout is also run
// without `contact` (CPU), where the lower lip passes through the upper one (4.3 mm at 4 mm).
TEST_P(LipContact, TheLipsDoNotPassThroughEachOther) {
  const auto& [name, device] = GetParam();
  if (device == "cuda" && !simulator::cuda_device_available()) GTEST_SKIP() << "no CUDA device";
  const ExpressionRun& r = run(name, device);
  const double with = min_lip_gap_mm(r);
  std::cout << name << " on " << device << ": smallest gap across the lips " << with
            << " mm with contact\n";
  // The run's own report of it (run_summary.json contact.min_gap_mm).
  EXPECT_GT(r.summary.contact_pairs, 0);
  EXPECT_NEAR(1e3 * r.summary.contact_min_gap, with, 1e-9);
  // Pressed together the lips yield by what the contact force moves a node in one step:
  // micrometres here (physics/lip_contact.hpp).
  EXPECT_GT(with, -0.01);
  if (name == "pout" && device == "cpu") {
    const double without = min_lip_gap_mm(run(name, "cpu", "sample_head_4mm", false));
    std::cout << name << ": smallest gap without contact " << without << " mm\n";
    EXPECT_LT(without, -1.0);
  }
}

INSTANTIATE_TEST_SUITE_P(SampleHead, LipContact,
                         ::testing::Combine(::testing::Values("smile", "pout", "oo", "chew"),
                                            ::testing::Values("cpu", "cuda")),
                         name_of);

// The real head scan (skipping when ../shared is absent): every expression runs to its end with
// no inversion, in one case (one voxelization of its 45,562 elements).
class FaceExpressionScan : public ::testing::TestWithParam<std::string> {};

TEST_P(FaceExpressionScan, EveryExpressionRunsWithNoInversion) {
  if (!std::filesystem::exists(kScan)) GTEST_SKIP() << "no " << kScan << " (../shared absent)";
  if (GetParam() == "cuda" && !simulator::cuda_device_available()) GTEST_SKIP() << "no CUDA device";
  voxelize_scan();
  for (const char* name : {"brow_raise", "frown", "smile", "sneer", "pout", "grimace"}) {
    SCOPED_TRACE(name);
    const ExpressionRun& r = run(name, GetParam(), "lee_perry_smith_4mm");
    EXPECT_EQ(r.summary.status, "completed");
    EXPECT_EQ(r.summary.steps_done, r.summary.steps_planned);
  }
  // The brow raise on a forehead of an adult's height (61 mm from the brow to the hairline; the
  // sample head's is 32.5): the brows rise as far as people raise theirs (7.6–9.0 mm, Cruz & Cruz
  // 2004, less the 1.5 mm people repeat an expression to) and the forehead's skin turns from
  // rising to descending within Cotofana's spread (61 ± 10% of the forehead's height). At 4 mm,
  // 0.1 s, CPU: the brows 7.8 and 9.9 mm, the turn at 64%.
  const Landmarks marks = read_landmarks(kSource / "data/landmarks/lee_perry_smith.yaml");
  const ExpressionRun& brow = run("brow_raise", GetParam(), "lee_perry_smith_4mm");
  const double share =
      c_line_share(brow, marks.points.at("brow_centre_left"), marks.points.at("hairline"));
  std::cout << "the scan's C-line on " << GetParam() << ": " << 100 * share << "%\n";
  EXPECT_GT(share, 0.51);
  EXPECT_LT(share, 0.71);
  for (const char* landmark : {"brow_centre_left", "brow_centre_right"}) {
    SCOPED_TRACE(landmark);
    EXPECT_GT(1e3 * skin_displacement(brow, marks.points.at(landmark))[1], 7.6 - 1.5);
  }
}

INSTANTIATE_TEST_SUITE_P(LeePerrySmith, FaceExpressionScan, ::testing::Values("cpu", "cuda"),
                         [](const ::testing::TestParamInfo<std::string>& i) { return i.param; });

// The GPU's scan spec (data/specs/lee_perry_smith_1.5mm.yaml: cropped to the face in front of the
// ears, from under the chin up) at the CI's 4 mm: no node behind z = -20 mm or below y = -40 mm by
// more than a voxel, the head only (narrower than 170 mm: the shoulders are 360 mm), the cut held
// rigid; the smile runs to its end on it with no inversion.
TEST(FaceExpressionCroppedScan, GpuSpecKeepsTheFaceAndSmiles) {
  if (!std::filesystem::exists(kScan)) GTEST_SKIP() << "no " << kScan << " (../shared absent)";
  const formats::Model m =
      voxelize_scan_spec("lee_perry_smith_1.5mm", "lee_perry_smith_crop_4mm", [](std::string& s) {
        const std::string res = "voxel_size: 1.5";
        const auto at = s.find(res);
        ASSERT_NE(at, std::string::npos);
        s.replace(at, res.size(), "voxel_size: 4");
      });
  double lo[3] = {1, 1, 1}, hi[3] = {-1, -1, -1};
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const auto p = m.node_position(formats::Index(n));
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
  }
  EXPECT_GT(lo[1], -40e-3 - 4e-3);
  EXPECT_GT(lo[2], -20e-3 - 4e-3);
  EXPECT_LT(hi[0] - lo[0], 170e-3);
  EXPECT_GT(m.rigid_nodes.size(), 500u);
  const ExpressionRun& r = run("smile", "cpu", "lee_perry_smith_crop_4mm");
  EXPECT_EQ(r.summary.status, "completed");
  EXPECT_EQ(r.summary.steps_done, r.summary.steps_planned);
}

}  // namespace
}  // namespace sinew::voxelizer
