// The whole pipeline: constraints, determinism, and the errors for bad input (through the library
// and through the sinew-voxelize tool, which must leave no model file behind).
#include "sinew/voxelizer/voxelize.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

#include "pipeline_test_util.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/voxelizer/primitives.hpp"

namespace sinew::voxelizer {
namespace {

using testing::expect_error;
using testing::run_spec;
using testing::TempDir;

const std::string kLayered = R"(
units: mm
resolution: {voxel_size: 0.8}
outer: {sphere: {radius: 8}, subdivisions: 4}
inner: {sphere: {radius: 4}, subdivisions: 4}
)" + testing::kPaperLayers + R"(muscles:
  - name: band
    mesh: {cylinder: {centre: [0, -6, 0], radius: 1, half_length: 3}, subdivisions: 2}
    material: muscle
    fibres: {type: harmonic, origin: {box: {min: [-2, -8, -3.5], max: [2, -4, -2]}},
             insertion: {box: {min: [-2, -8, 2], max: [2, -4, 3.5]}}}
tendons:
  - {name: cap, mesh: {cylinder: {centre: [0, -6, 3], radius: 1.2, half_length: 0.6}, subdivisions: 2}, material: tendon}
boundary:
  - {type: rigid, inside: true}
  - {type: sliding, within: 1.2}
node_sets:
  - {name: top, box: {min: [-9, -9, 7], max: [9, 9, 9]}}
  - {name: skin_nodes, surface: outer, distance: 0.5}
)";

TEST(Pipeline, RigidAndSlidingNodesFollowTheSkull) {
  const auto r = run_spec(kLayered, "layered.yaml");
  const auto& m = r.model;
  ASSERT_GT(m.rigid_nodes.size(), 0u);
  ASSERT_GT(m.sliding.size(), 0u);
  // The exact sphere stands in for the icosphere to within its chord error (r(1 - cos) ~ 0.05 mm).
  const double tol = 0.06e-3;
  for (auto n : m.rigid_nodes) {
    const auto p = m.node_position(n);
    EXPECT_LT(std::hypot(p[0], p[1], p[2]), 4e-3 + tol);
  }
  ASSERT_EQ(m.surfaces[0].role, formats::SurfaceRole::sliding);
  for (const auto& s : m.sliding) {
    const auto p = m.node_position(s.node);
    const double rho = std::hypot(p[0], p[1], p[2]);
    EXPECT_GT(rho, 4e-3 - tol);
    EXPECT_NEAR(s.rest_distance, rho - 4e-3, tol);
    EXPECT_LE(s.rest_distance, 1.2e-3);
    EXPECT_GE(s.rest_triangle, 0);
  }
  // Complete: every node clearly inside the skull is rigid, every node clearly within 1.2 mm of it
  // is sliding.
  std::vector<char> bound(m.node_count(), 0);
  for (auto n : m.rigid_nodes) bound[static_cast<std::size_t>(n)] = 1;
  for (const auto& s : m.sliding) bound[static_cast<std::size_t>(s.node)] = 2;
  for (std::size_t n = 0; n < m.node_count(); ++n) {
    const auto p = m.node_position(static_cast<formats::Index>(n));
    const double rho = std::hypot(p[0], p[1], p[2]);
    if (rho < 4e-3 - tol) {
      EXPECT_EQ(bound[n], 1) << "node " << n << " at r = " << rho;
    }
    if (rho > 4e-3 + tol && rho < 5.2e-3 - tol) {
      EXPECT_EQ(bound[n], 2) << "node " << n << " at r = " << rho;
    }
  }
  // Muscle and tendon: fractions, unit fibres, the tendon overriding the muscle's end.
  ASSERT_EQ(m.muscles.size(), 1u);
  double muscle = 0;
  for (std::size_t j = 0; j < m.muscles[0].elements.size(); ++j) {
    muscle += m.muscles[0].fractions[j];
    const auto& f = m.muscles[0].fibres[j];
    EXPECT_NEAR(std::hypot(f[0], f[1], f[2]), 1.0, 1e-12);
  }
  muscle *= std::pow(0.8e-3, 3);
  // Cylinder r = 1 mm from z = -3 to 3, minus the tendon cap from z = 2.4 to 3 (r = 1.2 > 1).
  const double expected = M_PI * 1e-6 * 5.4e-3 * 0.987;  // 0.987: the 32-gon's area
  EXPECT_NEAR(muscle / expected, 1.0, 0.03);
  EXPECT_GT(testing::material_volume(r.summary, "tendon"), 0);
  ASSERT_EQ(m.node_sets.size(), 2u);
  EXPECT_GT(m.node_sets[0].ids.size(), 0u);
  EXPECT_GT(m.node_sets[1].ids.size(), 0u);
  for (auto n : m.node_sets[0].ids) EXPECT_GE(m.node_position(n)[2], 7e-3);
  // Writes and reads back through the format's validator.
  TempDir dir;
  formats::write_model(m, (dir / "layered.h5").string());
  const auto back = formats::read_model((dir / "layered.h5").string());
  EXPECT_EQ(back.element_count(), m.element_count());
}

std::string read_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(Pipeline, DeterministicWhateverTheThreadCount) {
  TempDir dir;
  auto one = run_spec(kLayered, "layered.yaml", 1);
  auto two = run_spec(kLayered, "layered.yaml", 2);
  one.model.provenance.created.clear();
  two.model.provenance.created.clear();
  EXPECT_TRUE(one.model == two.model);
  formats::write_model(one.model, (dir / "one.h5").string());
  formats::write_model(two.model, (dir / "two.h5").string());
  const std::string a = read_bytes(dir / "one.h5"), b = read_bytes(dir / "two.h5");
  ASSERT_FALSE(a.empty());
  EXPECT_TRUE(a == b) << "model files differ between 1 and 2 threads";
}

TEST(Pipeline, TargetElementCountSetsTheVoxelSize) {
  std::string spec = kLayered;
  spec.replace(spec.find("{voxel_size: 0.8}"), 17, "{target_elements: 3000}");
  const auto r = run_spec(spec, "layered.yaml");
  EXPECT_GT(r.summary.elements, 3000 * 0.8);
  EXPECT_LT(r.summary.elements, 3000 * 1.6);  // plus the partial boundary voxels
}

TEST(Pipeline, DerivedInnerSurfaceFromTissueThickness) {
  const auto r = run_spec(R"(
units: mm
resolution: {voxel_size: 0.5}
outer: {sphere: {radius: 8}, subdivisions: 4}
tissue_thickness: 3
materials: {preset: warburton2013}
layers: [{material: dermis, thickness: 1}, {material: hypodermis}]
boundary: [{type: rigid, inside: true}, {type: sliding, within: 0.5}]
)",
                          "derived.yaml");
  const double mm3 = 1e-9;
  const double shell = 4.0 / 3 * M_PI * (512 - 125);
  EXPECT_NEAR(r.summary.tissue_volume / mm3 / shell, 1.0, 0.03);
  EXPECT_GT(r.summary.sliding_nodes, 0);
}

std::string with_outer(const std::string& outer, const std::string& extra = "") {
  return "units: mm\nresolution: {voxel_size: 1}\nouter: " + outer +
         "\nmaterials: {preset: warburton2013}\nlayers: [{material: dermis}]\n" + extra;
}

TEST(Pipeline, BadMeshesGiveSpecificErrors) {
  TempDir dir;
  // Missing file.
  EXPECT_NE(expect_error<IoError>(with_outer("missing.obj"), dir / "s.yaml").find("missing.obj"),
            std::string::npos);
  // Unknown format.
  dir.write("mesh.xyzq", "this is not a mesh\n");
  expect_error<FormatError>(with_outer("mesh.xyzq"), dir / "s.yaml");
  // Empty mesh.
  dir.write("empty.obj", "# nothing\n");
  expect_error<Error>(with_outer("empty.obj"), dir / "s.yaml");
  // NaN coordinates.
  dir.write("nan.obj",
            "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n");
  const std::string nan = expect_error<GeometryError>(with_outer("nan.obj"), dir / "s.yaml");
  EXPECT_NE(nan.find("finite"), std::string::npos) << nan;
  // Skull not inside the skin.
  const std::string skull = expect_error<GeometryError>(
      with_outer("{sphere: {radius: 5}}", "inner: {sphere: {centre: [8, 0, 0], radius: 4}}\n"),
      dir / "s.yaml");
  EXPECT_NE(skull.find("not inside the outer surface"), std::string::npos) << skull;
  // Muscle outside the tissue.
  const std::string muscle =
      expect_error<GeometryError>(with_outer("{sphere: {radius: 5}}", R"(muscles:
  - {name: far, mesh: {sphere: {centre: [20, 0, 0], radius: 2}}, material: muscle,
     fibres: {type: constant, direction: [1, 0, 0]}}
)"),
                                  dir / "s.yaml");
  EXPECT_NE(muscle.find("outside the tissue"), std::string::npos) << muscle;
}

TEST(Pipeline, MemoryEstimateIsCheckedBeforeAllocating) {
  TempDir dir;
  // 1 µm voxels over a 10 mm sphere: ~4e12 elements.
  const std::string msg = expect_error<ResourceError>(
      "units: mm\nresolution: {voxel_size: 0.001}\nouter: {sphere: {radius: 10}}\n"
      "materials: {preset: warburton2013}\nlayers: [{material: dermis}]\n",
      dir / "s.yaml");
  EXPECT_NE(msg.find("memory estimate"), std::string::npos) << msg;
  EXPECT_NE(msg.find("GiB"), std::string::npos) << msg;
  // A modest model refused under a tiny limit: the check does not depend on the machine.
  VoxelizeOptions small;
  small.memory_limit_bytes = 1024.0 * 1024;
  expect_error<ResourceError>(with_outer("{sphere: {radius: 5}}"), dir / "s.yaml", small);
}

// The tool: non-zero exit, a message naming the problem, no model file.
struct ToolRun {
  int status;
  std::string output;
};
ToolRun run_tool(const std::string& args, const TempDir& dir) {
  const std::string log = (dir / "tool.log").string();
  const std::string cmd = std::string(SINEW_VOXELIZE_EXE) + " " + args + " > " + log + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, ss.str()};
}

TEST(Tool, WritesTheModelAndPrintsTheSummary) {
  TempDir dir;
  dir.write("ok.yaml", with_outer("{sphere: {radius: 5}, subdivisions: 3}", "output: ok.h5\n"));
  const auto run = run_tool((dir / "ok.yaml").string() + " --quiet", dir);
  EXPECT_EQ(run.status, 0) << run.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "ok.h5"));
  const auto json =
      run_tool((dir / "ok.yaml").string() + " --json -o " + (dir / "j.h5").string(), dir);
  EXPECT_EQ(json.status, 0) << json.output;
  EXPECT_NE(json.output.find("\"elements\""), std::string::npos) << json.output;
  EXPECT_NE(json.output.find("\"stages\""), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(dir / "j.h5"));
}

TEST(Tool, BadInputExitsNonZeroAndWritesNothing) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"unknown_key.yaml", with_outer("{sphere: {radius: 5}}", "output: out.h5\ncolour: red\n")},
      {"missing_mesh.yaml", with_outer("nowhere.obj", "output: out.h5\n")},
      {"memory.yaml",
       "units: mm\noutput: out.h5\nresolution: {voxel_size: 0.001}\n"
       "outer: {sphere: {radius: 10}}\nmaterials: {preset: warburton2013}\n"
       "layers: [{material: dermis}]\n"},
      {"material.yaml",
       "units: mm\noutput: out.h5\nresolution: {voxel_size: 1}\n"
       "outer: {sphere: {radius: 10}}\nmaterials: {preset: warburton2013}\n"
       "layers: [{material: bone}]\n"},
  };
  const std::vector<std::string> expected = {"colour", "nowhere.obj", "memory estimate",
                                             "unknown material 'bone'"};
  for (std::size_t i = 0; i < cases.size(); ++i) {
    dir.write(cases[i].first, cases[i].second);
    const auto run = run_tool((dir / cases[i].first).string(), dir);
    EXPECT_NE(run.status, 0) << cases[i].first;
    EXPECT_NE(run.output.find(expected[i]), std::string::npos) << run.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "out.h5")) << cases[i].first;
  }
  const auto missing = run_tool((dir / "no_such_spec.yaml").string(), dir);
  EXPECT_NE(missing.status, 0);
  EXPECT_NE(missing.output.find("no_such_spec.yaml"), std::string::npos) << missing.output;
}

// --force reaches the library: a mesh 2.2 m long in a spec in mm is refused, naming the file,
// the extent and the units, and voxelized with a warning when forced (mesh_bounds_test.cpp).
TEST(Tool, ForceGoesPastTheBoundsOnTheMeshes) {
  TempDir dir;
  testing::write_obj(make_box({0, 0, 0}, {2200, 10, 10}, 0), dir / "long.obj");
  dir.write("long.yaml",
            "units: mm\noutput: out.h5\nresolution: {voxel_size: 5}\n"
            "outer: long.obj\nmaterials: {preset: warburton2013}\n"
            "layers: [{material: dermis}]\n");
  const auto refused = run_tool((dir / "long.yaml").string(), dir);
  EXPECT_EQ(refused.status, 1) << refused.output;
  EXPECT_NE(refused.output.find("long.obj: outer: the mesh spans 2200 mm"), std::string::npos)
      << refused.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out.h5"));
  const auto forced = run_tool((dir / "long.yaml").string() + " --force", dir);
  EXPECT_EQ(forced.status, 0) << forced.output;
  EXPECT_NE(forced.output.find("going on (--force)"), std::string::npos) << forced.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out.h5"));
}

}  // namespace
}  // namespace sinew::voxelizer
