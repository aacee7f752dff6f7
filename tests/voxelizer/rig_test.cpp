// The muscle rig (voxelizer/sinew/voxelizer/rig.hpp, docs/faces.md): the landmark format and its
// validator, the sample head, the rig's closed muscle meshes, their mirror symmetry and depth, the
// checks naming landmarks off the skin and muscles outside the tissue, circumferential fibres.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <set>
#include <sstream>
#include <string>
#include <tuple>

#include "pipeline_test_util.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/voxelizer/fibres.hpp"
#include "sinew/voxelizer/head.hpp"
#include "sinew/voxelizer/landmarks.hpp"
#include "sinew/voxelizer/rig.hpp"
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"
#include "sinew/voxelizer/winding_number.hpp"

namespace sinew::voxelizer {
namespace {

using testing::TempDir;
const std::filesystem::path kSource = SINEW_SOURCE_DIR;

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A head in metres (the rig works in metres), at a coarser mesh than the shipped one for speed.
const TriangleMesh& skin_m() {
  static const TriangleMesh m = [] {
    TriangleMesh s = make_head(HeadParams{}).skin;
    for (auto& v : s.vertices) v = 1e-3 * v;
    return s;
  }();
  return m;
}

// Rounded positions, x mirrored when `mirror`, as a set: compares vertex sets up to 1 µm.
std::set<std::tuple<long, long, long>> positions(const TriangleMesh& m, bool mirror) {
  std::set<std::tuple<long, long, long>> s;
  for (const auto& v : m.vertices) {
    s.insert(
        {std::lround((mirror ? -v.x : v.x) * 1e6), std::lround(v.y * 1e6), std::lround(v.z * 1e6)});
  }
  return s;
}

std::string sample_landmarks_text() {
  return landmarks_yaml(head_landmarks(HeadParams{}), LengthUnit::mm);
}

TEST(Landmarks, TwentyNamedPointsEachDescribed) {
  EXPECT_EQ(landmark_names().size(), 20u);
  for (const auto& n : landmark_names()) EXPECT_FALSE(landmark_description(n).empty()) << n;
}

TEST(Landmarks, FileRoundTripsToTheWrittenPrecision) {
  const Landmarks a = head_landmarks(HeadParams{});
  const Landmarks b = parse_landmarks(landmarks_yaml(a, LengthUnit::mm), "x.yaml");
  for (const auto& n : landmark_names()) EXPECT_LT(norm(a.at(n) - b.at(n)), 1e-6) << n;
  EXPECT_EQ(b.mesh, "skin.obj");
}

TEST(Landmarks, CommittedSampleFileIsWhatSinewHeadWrites) {
  const TempDir dir;
  write_head(HeadParams{}, dir.path());
  EXPECT_EQ(read(dir / "landmarks.yaml"), read(kSource / "data/landmarks/sample_head.yaml"))
      << "regenerate: sinew-head -o DIR && cp DIR/landmarks.yaml data/landmarks/sample_head.yaml";
}

TEST(Landmarks, ValidatorNamesTheProblem) {
  const std::string good = sample_landmarks_text();
  auto message = [](const std::string& text) {
    try {
      parse_landmarks(text, "bad.yaml");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  std::string typo = good;
  typo.replace(typo.find("  chin:"), 7, "  chinn:");
  EXPECT_NE(message(typo).find("unknown key 'chinn'"), std::string::npos) << message(typo);
  std::string missing = good.substr(0, good.find("  chin:"));
  EXPECT_NE(message(missing).find("missing landmark 'chin'"), std::string::npos);
  std::string version = good;
  version.replace(version.find("version: 1"), 10, "version: 2");
  EXPECT_NE(message(version).find("unsupported version 2"), std::string::npos);
  std::string format = good;
  format.replace(format.find("sinew-landmarks"), 15, "other-landmarks");
  EXPECT_NE(message(format).find("expected format 'sinew-landmarks'"), std::string::npos);
  std::string extra = good + "colour: red\n";
  EXPECT_NE(message(extra).find("unknown key 'colour'"), std::string::npos);
  std::string nan = good;
  nan.replace(nan.find("[0.000, 64.279"), 14, "[.nan, 64.279");
  EXPECT_NE(message(nan), "no error");
}

TEST(SampleHead, ClosedOutwardMirrorSymmetricSkullInside) {
  const HeadMeshes m = make_head(HeadParams{});
  for (const TriangleMesh* mesh : {&m.skin, &m.skull}) {
    SCOPED_TRACE(mesh->source);
    const MeshDiagnostics d = describe_mesh(*mesh);
    EXPECT_TRUE(d.closed);
    EXPECT_EQ(d.inconsistently_oriented_edges, 0);
    EXPECT_EQ(d.components, 1);
    EXPECT_GT(d.enclosed_volume, 0);
    EXPECT_EQ(positions(*mesh, false), positions(*mesh, true));
  }
  // Every skull vertex inside the skin, 6 mm or more below it (the thinnest tissue).
  const WindingNumber skin(m.skin);
  for (std::size_t v = 0; v < m.skull.vertices.size(); v += 97) {
    EXPECT_TRUE(skin.inside(m.skull.vertices[v])) << v;
  }
  // Every landmark on the skin mesh (its facets lie within 0.25 mm of the smooth surface at the
  // nose's tip, the most curved place).
  for (const auto& [name, d] : landmark_distances(head_landmarks(HeadParams{}), skin_m())) {
    EXPECT_LT(d, 2.5e-4) << name;
  }
}

const std::vector<RigMuscle>& sample_rig() {
  static const std::vector<RigMuscle> r =
      build_rig(rig_recipes(head_landmarks(HeadParams{}), rig_muscle_names(), 1.0), skin_m(), 3e-3);
  return r;
}

TEST(Rig, EighteenClosedOutwardMusclesWithFibres) {
  const auto& rig = sample_rig();
  ASSERT_EQ(rig.size(), 18u);  // 8 pairs + orbicularis oris + mentalis
  for (const auto& m : rig) {
    SCOPED_TRACE(m.name);
    const MeshDiagnostics d = describe_mesh(m.mesh);
    EXPECT_TRUE(d.closed);
    EXPECT_EQ(d.non_manifold_edges, 0);
    EXPECT_EQ(d.inconsistently_oriented_edges, 0);
    EXPECT_GT(d.enclosed_volume, 50e-9);  // > 50 mm³
    const bool ring = m.name.rfind("orbicularis", 0) == 0;
    EXPECT_EQ(m.fibres.kind, ring ? FibreSpec::Kind::circumferential : FibreSpec::Kind::harmonic);
  }
}

TEST(Rig, LeftAndRightMusclesAreMirrorImages) {
  const auto& rig = sample_rig();
  auto find = [&](const std::string& n) -> const RigMuscle& {
    for (const auto& m : rig)
      if (m.name == n) return m;
    throw std::runtime_error("no muscle " + n);
  };
  for (const auto& base : rig_muscle_names()) {
    SCOPED_TRACE(base);
    if (base == "orbicularis_oris" || base == "mentalis") {
      EXPECT_EQ(positions(find(base).mesh, false), positions(find(base).mesh, true));
    } else {
      EXPECT_EQ(positions(find(base + "_left").mesh, false),
                positions(find(base + "_right").mesh, true));
    }
  }
}

// Each muscle lies in the tissue: below the skin by at least its top depth, above the skull.
TEST(Rig, MusclesLieUnderTheSkinAboveTheSkull) {
  const HeadMeshes m = make_head(HeadParams{});
  TriangleMesh skull = m.skull;
  for (auto& v : skull.vertices) v = 1e-3 * v;
  const WindingNumber outer(skin_m()), inner(skull);
  for (const auto& mu : sample_rig()) {
    std::size_t in = 0;
    for (const auto& p : mu.samples) in += (outer.inside(p) && !inner.inside(p)) ? 1 : 0;
    EXPECT_GE(static_cast<double>(in) / static_cast<double>(mu.samples.size()), 0.9) << mu.name;
  }
}

// The spec with a rig, written next to a generated head (metres → the spec's mm).
std::filesystem::path rig_spec(const TempDir& dir, const std::string& rig_extra,
                               const std::string& landmarks_text) {
  write_head(HeadParams{}, dir.path());
  dir.write("lm.yaml", landmarks_text);
  return dir.write("spec.yaml",
                   "units: mm\nresolution: {voxel_size: 4}\n"
                   "outer: skin.obj\ninner: skull.obj\n"
                   "materials: {preset: warburton2013}\n"
                   "layers: [{material: dermis, thickness: 2}, {material: hypodermis}]\n"
                   "rig: {landmarks: lm.yaml" +
                       rig_extra + "}\n");
}

TEST(RigChecks, LandmarkOffTheSkinIsNamedWithItsDistance) {
  const TempDir dir;
  Landmarks l = head_landmarks(HeadParams{});
  l.points["nose_tip"].z += 7e-3;  // 7 mm in front of the nose
  Spec spec = read_spec(rig_spec(dir, "", landmarks_yaml(l, LengthUnit::mm)));
  try {
    add_rig_muscles(spec);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("nose_tip is 7.0 mm off the skin"), std::string::npos) << w;
    EXPECT_EQ(w.find("chin"), std::string::npos) << w;  // only the one off the skin
  }
}

TEST(RigChecks, MusclesOutsideTheTissueAreNamedWithTheirShare) {
  const TempDir dir;
  // Three times the anatomical depths puts the deep muscles into the skull.
  Spec spec = read_spec(rig_spec(dir, ", depth_scale: 3", sample_landmarks_text()));
  try {
    add_rig_muscles(spec);
    FAIL() << "no error";
  } catch (const GeometryError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("zygomaticus_major_left only"), std::string::npos) << w;
    EXPECT_NE(w.find("% inside"), std::string::npos) << w;
  }
}

TEST(RigChecks, AtAnatomicalDepthsEveryMuscleIsAdded) {
  const TempDir dir;
  Spec spec = read_spec(
      rig_spec(dir, ", muscles: [zygomaticus_major, orbicularis_oris]", sample_landmarks_text()));
  add_rig_muscles(spec);
  ASSERT_EQ(spec.muscles.size(), 3u);
  EXPECT_EQ(spec.muscles[0].name, "orbicularis_oris");  // the sphincter first (rig_spec.hpp)
  EXPECT_EQ(spec.muscles[0].fibres.kind, FibreSpec::Kind::circumferential);
  EXPECT_EQ(spec.muscles[1].name, "zygomaticus_major_left");
  EXPECT_EQ(spec.muscles[2].name, "zygomaticus_major_right");
}

TEST(RigSpec, UnknownKeysAndMusclesAreRefused) {
  const TempDir dir;
  auto message = [&](const std::string& extra) {
    try {
      read_spec(rig_spec(dir, extra, sample_landmarks_text()));
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(", musles: all").find("unknown key 'musles'"), std::string::npos);
  EXPECT_NE(message(", muscles: [zygomaticus]").find("unknown rig muscle 'zygomaticus'"),
            std::string::npos);
  EXPECT_NE(message(", material: bone").find("unknown material 'bone'"), std::string::npos);
  EXPECT_NE(message(", min_inside: 1.5").find("must be in (0, 1]"), std::string::npos);
}

// Circumferential fibres: tangent to the ellipses (x/A)² + (y/B)² = const about the axis.
TEST(CircumferentialFibres, TangentToTheEllipsesAroundTheAxis) {
  const Vec3d c{0.01, -0.02, 0.03}, axis{0, 0, 1}, major{1, 0, 0};
  const double a = 0.02, b = 0.008;
  for (int k = 0; k < 16; ++k) {
    const double t = 2 * std::numbers::pi * (k + 0.3) / 16;
    for (const double s : {0.3, 1.0, 1.7}) {
      const Vec3d p = c + Vec3d{s * a * std::cos(t), s * b * std::sin(t), 0.004};
      const Vec3d f = circumferential_fibre(p, c, axis, major, a, b);
      const Vec3d tangent{-a * std::sin(t), b * std::cos(t), 0};
      EXPECT_NEAR(norm(f), 1.0, 1e-12);
      EXPECT_NEAR(std::abs(dot(f, tangent)) / norm(tangent), 1.0, 1e-12) << k << " " << s;
      EXPECT_NEAR(dot(f, axis), 0.0, 1e-12);
    }
  }
  // On the axis: the tangent at the major axis' ends.
  const Vec3d f0 = circumferential_fibre(c, c, axis, major, a, b);
  EXPECT_NEAR(std::abs(f0.y), 1.0, 1e-12);
}

TEST(CircumferentialFibres, SpecReadsAndChecksThem) {
  const TempDir dir;
  dir.write("m.yaml", "");
  auto spec = [&](const std::string& fibres) {
    return parse_spec(
        "units: mm\nresolution: {voxel_size: 1}\nouter: {sphere: {radius: 10}}\n"
        "layers: [{material: m}]\n"
        "materials: {table: {m: {youngs_modulus: 1, poisson_ratio: 0.3, density: 1}}}\n"
        "muscles: [{name: ring, mesh: {sphere: {radius: 5}}, material: m, fibres: " +
            fibres + "}]\n",
        dir / "s.yaml");
  };
  const Spec s = spec(
      "{type: circumferential, centre: [1, 2, 3], axis: [0, 0, 2], major: [1, 1, 0], "
      "radii: [4, 2]}");
  const auto& f = s.muscles[0].fibres;
  EXPECT_EQ(f.kind, FibreSpec::Kind::circumferential);
  EXPECT_NEAR(f.centre.y, 2e-3, 1e-15);
  EXPECT_NEAR(f.axis.z, 1.0, 1e-15);
  EXPECT_NEAR(f.major.x, std::sqrt(0.5), 1e-15);
  EXPECT_DOUBLE_EQ(f.radius_major / f.radius_minor, 2.0);
  EXPECT_THROW(spec("{type: circumferential, centre: [0, 0, 0]}"), ConfigError);  // no axis
  try {
    spec(
        "{type: circumferential, centre: [0, 0, 0], axis: [0, 0, 1], origin: {box: {min: [0, 0, "
        "0], max: [1, 1, 1]}}}");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("a circumferential fibre field has no origin"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(
      spec("{type: circumferential, centre: [0, 0, 0], axis: [1, 0, 0], major: [2, 0, 0]}"),
      ConfigError);  // major along the axis
}

// Snapping puts every landmark on the skin: one 12 mm off it lands on the skin's closest point,
// the others (on the skin already, within its facets' 0.25 mm of the smooth surface) barely move.
TEST(Rig, SnappedLandmarksLieOnTheSkin) {
  Landmarks l = head_landmarks(HeadParams{});
  l.points["chin"].y -= 12e-3;
  const Landmarks s = snap_landmarks(l, skin_m());
  for (const auto& [name, d] : landmark_distances(s, skin_m())) EXPECT_LT(d, 1e-9) << name;
  EXPECT_GT(norm(s.at("chin") - l.at("chin")), 5e-3);
  for (const auto& name : landmark_names()) {
    if (name == "chin") continue;
    EXPECT_LT(norm(s.at(name) - l.at(name)), 2.5e-4) << name;
  }
}

// The tools: sinew-head writes the head and its landmarks; sinew-rig builds the rig from a spec,
// writes its 18 muscles as closed OBJ files and the three pictures (landmarks, muscles, jaw; the
// jaw's refused on a rig without one); a landmark off the skin makes it
// fail with the landmark's name, the landmarks' picture drawn (to correct it by eye) and not the
// muscles'; --snap-landmarks writes the points moved onto the skin and builds the rig from them.
int tool(const std::string& exe, const std::string& args, const std::filesystem::path& log) {
  const std::string cmd = exe + " " + args + " > " + log.string() + " 2>&1";
  return WEXITSTATUS(std::system(cmd.c_str()));
}

TEST(RigTools, HeadAndRigWriteMeshesAndPictures) {
  const TempDir dir;
  ASSERT_EQ(tool(SINEW_HEAD_EXE, "-o " + (dir / "meshes/head").string(), dir / "head.log"), 0)
      << read(dir / "head.log");
  for (const char* f : {"skin.obj", "skull.obj", "skull_glide.obj", "landmarks.yaml"})
    EXPECT_TRUE(std::filesystem::exists(dir / "meshes/head" / f)) << f;
  std::filesystem::create_directories(dir / "specs");
  std::filesystem::create_directories(dir / "landmarks");
  std::filesystem::copy_file(kSource / "data/specs/sample_head_4mm.yaml",
                             dir / "specs/sample_head_4mm.yaml");
  std::filesystem::copy_file(dir / "meshes/head/landmarks.yaml",
                             dir / "landmarks/sample_head.yaml");
  const std::string spec = (dir / "specs/sample_head_4mm.yaml").string();
  ASSERT_EQ(tool(SINEW_RIG_EXE,
                 spec + " -o " + (dir / "rig").string() + " --landmarks-png " +
                     (dir / "l.png").string() + " --muscles-png " + (dir / "m.png").string() +
                     " --jaw-png " + (dir / "j.png").string(),
                 dir / "rig.log"),
            0)
      << read(dir / "rig.log");
  int objs = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir / "rig")) {
    TriangleMesh m = load_mesh(e.path());
    EXPECT_TRUE(describe_mesh(m).closed) << e.path();
    ++objs;
  }
  EXPECT_EQ(objs, 18);
  EXPECT_GT(std::filesystem::file_size(dir / "l.png"), 10000u);
  EXPECT_GT(std::filesystem::file_size(dir / "m.png"), 10000u);
  EXPECT_GT(std::filesystem::file_size(dir / "j.png"), 10000u);
  // --jaw-png on a rig without a jaw: an error naming rig.jaw, no picture.
  std::string no_jaw = read(spec);
  const auto at = no_jaw.find("jaw: true");
  ASSERT_NE(at, std::string::npos);
  no_jaw.replace(at, 9, "jaw: false");
  const auto no_jaw_spec = dir.write("specs/no_jaw.yaml", no_jaw);
  EXPECT_EQ(tool(SINEW_RIG_EXE,
                 no_jaw_spec.string() + " -o " + (dir / "rig4").string() + " --jaw-png " +
                     (dir / "j4.png").string(),
                 dir / "rig4.log"),
            1);
  EXPECT_NE(read(dir / "rig4.log").find("rig.jaw"), std::string::npos) << read(dir / "rig4.log");
  EXPECT_FALSE(std::filesystem::exists(dir / "j4.png"));

  Landmarks l = head_landmarks(HeadParams{});
  l.points["chin"].y -= 12e-3;  // 12 mm below the chin, in the air
  dir.write("landmarks/sample_head.yaml", landmarks_yaml(l, LengthUnit::mm));
  EXPECT_EQ(tool(SINEW_RIG_EXE,
                 spec + " -o " + (dir / "rig2").string() + " --landmarks-png " +
                     (dir / "l2.png").string() + " --muscles-png " + (dir / "m2.png").string(),
                 dir / "rig2.log"),
            1);
  EXPECT_NE(read(dir / "rig2.log").find("chin is"), std::string::npos) << read(dir / "rig2.log");
  EXPECT_GT(std::filesystem::file_size(dir / "l2.png"), 10000u);
  EXPECT_FALSE(std::filesystem::exists(dir / "m2.png"));

  const auto snapped = dir / "snapped.yaml";
  ASSERT_EQ(tool(SINEW_RIG_EXE,
                 spec + " -o " + (dir / "rig3").string() + " --snap-landmarks " + snapped.string(),
                 dir / "rig3.log"),
            0)
      << read(dir / "rig3.log");
  EXPECT_NE(read(dir / "rig3.log").find("snapped chin"), std::string::npos)
      << read(dir / "rig3.log");
  const Landmarks s = read_landmarks(snapped);
  EXPECT_GT(norm(s.at("chin") - l.at("chin")), 5e-3);
  EXPECT_LT(norm(s.at("nose_tip") - l.at("nose_tip")), 5e-4);
  EXPECT_TRUE(std::filesystem::exists(dir / "rig3/mentalis.obj"));
}

// A failing check still draws the muscles (issue 34, item 3: the picture is how a misplaced muscle
// is seen) and says where the rest of each muscle lies and what helps: three times the depths
// put the deep muscles into the skull.
TEST(RigTools, AFailingCheckStillDrawsTheMusclesAndSaysWhereTheyLie) {
  const TempDir dir;
  const std::filesystem::path spec_path =
      rig_spec(dir, ", muscles: [zygomaticus_major], depth_scale: 3", sample_landmarks_text());
  ASSERT_EQ(tool(SINEW_RIG_EXE,
                 spec_path.string() + " -o " + (dir / "rig").string() + " --muscles-png " +
                     (dir / "m.png").string(),
                 dir / "rig.log"),
            1);
  const std::string log = read(dir / "rig.log");
  EXPECT_NE(log.find("zygomaticus_major_left only"), std::string::npos) << log;
  EXPECT_NE(log.find("% in the skull)"), std::string::npos) << log;
  EXPECT_NE(log.find("scale the depths with rig.depth_scale"), std::string::npos) << log;
  EXPECT_EQ(log.find("beyond the mesh"), std::string::npos) << log;  // nothing past the skin
  EXPECT_NE(log.find("drew the muscles to"), std::string::npos) << log;
  EXPECT_GT(std::filesystem::file_size(dir / "m.png"), 10000u);
  EXPECT_FALSE(std::filesystem::exists(dir / "rig/zygomaticus_major_left.obj"));
}

}  // namespace
}  // namespace sinew::voxelizer
