// The sample models and scenes (docs/sample-models.md): the boundary visual surface, the models'
// sets and sizes, the physics of data/scenes/skin_block_press.yaml and soft_body_gravity.yaml on
// small versions of their models (every backend in kBackends; CUDA skips without a device), and the
// sinew-sample-model tool checked by sinew-inspect.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "engine_test_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/validate.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"
#include "sinew/simulator/run/scene.hpp"
#ifdef SINEW_CUDA_ENABLED
#include "sinew/simulator/engine/cuda_backend.hpp"
#endif

namespace sinew::simulator::testing {
namespace {
namespace fs = std::filesystem;
using SimSetup = sinew::simulator::Setup;

const std::vector<NamedBackend>& kBackends = every_backend();

// string_view, not const std::string&: g++ 13 warns of a dangling reference when a function returning
// a reference takes a temporary string.
const formats::Surface& surface_named(const formats::Model& m, std::string_view name) {
  for (const auto& s : m.surfaces)
    if (s.name == name) return s;
  throw std::runtime_error("no surface " + std::string(name));
}
const formats::NamedSet& node_set(const formats::Model& m, std::string_view name) {
  for (const auto& s : m.node_sets)
    if (s.name == name) return s;
  throw std::runtime_error("no node set " + std::string(name));
}

// Σ over triangles of v0 · (v1 × v2) / 6: the enclosed volume of a closed, outward surface.
double enclosed_volume(const formats::Surface& s) {
  double v = 0;
  for (const auto& t : s.triangles) {
    const auto& a = s.vertices[std::size_t(t[0])];
    const auto& b = s.vertices[std::size_t(t[1])];
    const auto& c = s.vertices[std::size_t(t[2])];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
          a[2] * (b[0] * c[1] - b[1] * c[0])) /
         6;
  }
  return v;
}

// Largest distance between a visual vertex and the hex8 interpolation of its element's nodes at
// its natural coordinates (model-format.md), m.
double embedding_error(const formats::Model& m, const formats::Surface& s) {
  double worst = 0;
  for (std::size_t v = 0; v < s.vertices.size(); ++v) {
    const auto& nodes = m.element_nodes[std::size_t(s.embedding_element[v])];
    const auto& xi = s.embedding_local[v];
    std::array<double, 3> x{};
    for (int a = 0; a < 8; ++a) {
      const auto& c = formats::kHexCorner[std::size_t(a)];
      const double n = (1 + (2 * c[0] - 1) * xi[0]) * (1 + (2 * c[1] - 1) * xi[1]) *
                       (1 + (2 * c[2] - 1) * xi[2]) / 8;
      const auto p = m.node_position(nodes[std::size_t(a)]);
      for (int k = 0; k < 3; ++k) x[std::size_t(k)] += n * p[std::size_t(k)];
    }
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, std::abs(x[std::size_t(k)] - s.vertices[v][std::size_t(k)]));
  }
  return worst;
}

// ---- models ------------------------------------------------------------------------------------

TEST(SampleModels, BoundarySurfaceIsClosedOutwardAndBound) {
  // The soft body (one connected piece) and a full block: the surface encloses exactly the
  // elements' volume (positive: triangles face outwards), and every vertex sits at its embedding.
  formats::Model body = make_soft_body_sample_model(0.5425, 4e-3);
  const double h = body.grid.voxel_size;
  const auto& skin = surface_named(body, "skin");
  EXPECT_EQ(skin.role, formats::SurfaceRole::visual);
  EXPECT_NEAR(enclosed_volume(skin), double(body.element_count()) * h * h * h,
              1e-9 * double(body.element_count()) * h * h * h);
  EXPECT_LT(embedding_error(body, skin), 1e-15);
  EXPECT_NO_THROW(formats::validate_model(body, "body"));

  formats::Model block = make_skin_block_model(5, 4, 3, 1e-3);
  add_boundary_visual_surface(block, "all_faces");
  const auto& all = surface_named(block, "all_faces");
  EXPECT_NEAR(enclosed_volume(all), 60e-9, 1e-20);
  EXPECT_EQ(all.vertices.size(), std::size_t(6 * 5 * 4 - 4 * 3 * 2));  // lattice minus interior
  EXPECT_EQ(all.triangles.size(), std::size_t(4 * (5 * 4 + 5 * 3 + 4 * 3)));
  EXPECT_THROW(add_boundary_visual_surface(block, "all_faces"), sinew::ConfigError);
  EXPECT_THROW(add_boundary_visual_surface(block, "other", "no_such_set"), sinew::ConfigError);
}

TEST(SampleModels, SkinBlockSizesSetsAndSurface) {
  // Paper size (Table 2): 120 × 120 × 9 voxels, 129,600 elements, 146,410 nodes; a 13 × 13 node
  // press patch at the top centre; the skin is the boundary without the bottom face.
  const formats::Model paper = make_skin_block_sample_model();
  EXPECT_EQ(paper.element_count(), 129600u);
  EXPECT_EQ(paper.node_count(), 146410u);
  EXPECT_EQ(paper.materials.size(), 3u);
  EXPECT_EQ(node_set(paper, "press").ids.size(), 169u);
  const auto& skin = surface_named(paper, "skin");
  EXPECT_EQ(skin.vertices.size(), std::size_t(121 * 121 + 4 * 120 * 9));
  EXPECT_EQ(skin.triangles.size(), std::size_t(2 * (120 * 120 + 4 * 120 * 9)));

  const formats::Model small = make_skin_block_sample_model(12, 12, 5, 0.5e-3, 2);
  const auto& press = node_set(small, "press");
  ASSERT_EQ(press.ids.size(), 9u);
  for (const Index n : press.ids) {
    const auto p = small.node_position(n);
    EXPECT_NEAR(p[2], 2.5e-3, 1e-15);
    EXPECT_LE(std::abs(p[0] - 3e-3), 0.5e-3 + 1e-15);
    EXPECT_LE(std::abs(p[1] - 3e-3), 0.5e-3 + 1e-15);
  }
}

TEST(SampleModels, SoftBodyIsOnePieceOnFlatFeet) {
  // Default size: ≈ 16k elements, feet on the floor (lattice k = 0), all of them in the four pads.
  const formats::Model body = make_soft_body_sample_model();
  EXPECT_EQ(body.element_count(), 16354u);
  EXPECT_EQ(body.node_count(), 20992u);
  const auto& feet = node_set(body, "feet");
  EXPECT_GT(feet.ids.size(), 4u * 40u);
  int quadrant[4] = {0, 0, 0, 0};
  for (const Index n : feet.ids) {
    const auto p = body.node_position(n);
    quadrant[(p[0] > 0 ? 1 : 0) + (p[1] > 0 ? 2 : 0)]++;
  }
  for (int q : quadrant) EXPECT_EQ(q, int(feet.ids.size()) / 4);
  // The closed skin encloses every element: no piece is left out of it or floats apart.
  const auto& skin = surface_named(body, "skin");
  const double h = body.grid.voxel_size;
  EXPECT_NEAR(enclosed_volume(skin), double(body.element_count()) * h * h * h, 1e-12);
  EXPECT_NEAR(model_mass(body), 1000.0 * double(body.element_count()) * h * h * h, 1e-12);
}

// ---- scenes on small models ---------------------------------------------------------------------

class SampleScene : public BackendTest<NamedBackend> {
 protected:
  // The scene file of data/scenes resolved against `model` (its own model file is not read).
  ResolvedScene resolve(const std::string& file, const formats::Model& model) {
    const Scene scene = parse_scene(std::string(SINEW_SOURCE_DIR) + "/data/scenes/" + file);
    return resolve_scene(scene, model);
  }
};

TEST_P(SampleScene, SoftBodyFeetCarryItsWeightAfterSettling) {
  // The soft body at the default's physical size, half the resolution (h = 4 mm, 2,060 elements):
  // the scene's 0.4 s with its damping. Once settled the feet's reaction is the weight
  // W = Σ ρ g V (physical ρ), upwards: vertical within 0.2 % of W, horizontal below 1 % of W (the
  // residual is the inertia and damping force of the last, slowest creep: a sway mode, overdamped);
  // kinetic energy < 1e-4 of the strain energy.
  const formats::Model body = make_soft_body_sample_model(0.5425, 4e-3);
  const ResolvedScene rs = resolve("soft_body_gravity.yaml", body);
  ASSERT_TRUE(rs.setup.effects.gravity);
  auto b = GetParam().make(body, rs.setup);
  const auto steps = std::int64_t(std::ceil(rs.setup.duration / b->dt()));
  b->step(steps);
  const double weight = model_mass(body) * 9.81;
  const auto r = b->reaction(node_set(body, "feet").ids);
  std::printf("soft body: %zu elements, W = %.6f N, feet reaction (%.3g, %.3g, %.6f) N\n",
              body.element_count(), weight, r[0], r[1], r[2]);
  EXPECT_LT(std::abs(r[2] - weight), 2e-3 * weight);
  EXPECT_LT(std::hypot(r[0], r[1]), 0.01 * weight);
  const auto e = b->energies();
  EXPECT_LT(e.kinetic, 1e-4 * e.strain);
  // Clapeyron: at rest under a dead load a linear elastic body stores half the load's work,
  // U = ½ W_ext (W_ext = Σ m g · u here). The sag is not small (large rotations of the tail), so
  // the stored energy (strain + hourglass) is checked to 2 % of ½ W_ext (measured: 0.04 %).
  std::printf("soft body: strain + hourglass %.6g J, external work / 2 %.6g J\n",
              e.strain + e.hourglass, 0.5 * e.external_work);
  EXPECT_NEAR((e.strain + e.hourglass) / (0.5 * e.external_work), 1.0, 0.02);
  // It sagged: some part (the tail) moved down by more than 1 mm.
  const auto u = b->displacements();
  double lowest = 0;
  for (std::size_t n = 0; n < body.node_count(); ++n) lowest = std::min(lowest, u[3 * n + 2]);
  EXPECT_LT(lowest, -1e-3);
}

TEST_P(SampleScene, PressedBlockBaseCarriesTheForceInTheHold) {
  // A 6 × 6 mm block of the same layers at h = 0.5 mm (720 elements) with a 1 mm patch; the
  // scene's force scaled by the patch area (1/9 of the 3 mm patch), same pressure. At the end of
  // the hold (t just below 10 ms) the base carries the applied force; after the release and the
  // 6 ms free it carries none. Tolerance 1 % of the force.
  const formats::Model block = make_skin_block_sample_model(12, 12, 5, 0.5e-3, 2);
  ResolvedScene rs = resolve("skin_block_press.yaml", block);
  ASSERT_EQ(rs.setup.forces.size(), 1u);
  auto& force = rs.setup.forces[0];
  force.total[2] /= 9;
  const double f = force.total[2];
  ASSERT_LT(f, 0);
  auto b = GetParam().make(block, rs.setup);
  const auto& base = node_set(block, "z_min").ids;
  b->step(std::int64_t(0.0099 / b->dt()));
  ASSERT_DOUBLE_EQ(force.curve.at(b->time()), 1.0);
  auto r = b->reaction(base);
  std::printf("press: applied %.6f N, base reaction (%.3g, %.3g, %.6f) N at t = %.5f s\n", f, r[0],
              r[1], r[2], b->time());
  EXPECT_LT(std::hypot(r[0], r[1], r[2] + f), 0.01 * std::abs(f));
  const auto rp = b->reaction(node_set(block, "press").ids);  // free nodes: no reaction
  EXPECT_LT(std::hypot(rp[0], rp[1], rp[2]), 0.01 * std::abs(f));
  const auto u = b->displacements();
  const auto& patch = node_set(block, "press").ids;
  EXPECT_LT(u[3 * std::size_t(patch[4]) + 2], -0.05e-3);  // the centre is pressed in
  // Clapeyron: the stored energy is half the work the final force does on the final displacement,
  // U = ½ Σ f · u (linear elasticity; 2 % for the indentation's nonlinearity; measured 0.5 %).
  double half_work = 0;
  for (const Index n : patch)
    half_work += 0.5 * f / double(patch.size()) * u[3 * std::size_t(n) + 2];
  const auto e = b->energies();
  std::printf("press: strain + hourglass %.6g J, ½ f·u %.6g J\n", e.strain + e.hourglass,
              half_work);
  EXPECT_NEAR((e.strain + e.hourglass) / half_work, 1.0, 0.02);
  b->step(std::int64_t(std::ceil(rs.setup.duration / b->dt())) - b->step_index());
  r = b->reaction(base);
  EXPECT_LT(std::hypot(r[0], r[1], r[2]), 0.01 * std::abs(f));
}

INSTANTIATE_TEST_SUITE_P(Backends, SampleScene, ::testing::ValuesIn(kBackends), backend_name);

// ---- the tool ----------------------------------------------------------------------------------

std::string run(const std::string& command, int& status) {
  std::string out;
  std::FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return out;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, p)) out += buf;
  const int rc = pclose(p);
  status = WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  return out;
}

TEST(SampleModelTool, WritesModelsThatSinewInspectAccepts) {
  const fs::path dir =
      fs::temp_directory_path() / ("sinew_sample_model_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string tool = SINEW_SAMPLE_MODEL_EXE, inspect = SINEW_INSPECT_EXE;
  int rc = -1;
  const std::string help = run(tool + " --help", rc);
  EXPECT_EQ(rc, 0);
  EXPECT_NE(help.find("skin-block"), std::string::npos);
  EXPECT_NE(help.find("soft-body"), std::string::npos);
  const std::string block = (dir / "block.h5").string(), body = (dir / "body.h5").string();
  run(tool + " skin-block --dims 12 12 5 --voxel-size 0.0005 --press-width 2 -q -o " + block, rc);
  EXPECT_EQ(rc, 0);
  run(tool + " soft-body --scale 0.5425 --voxel-size 0.004 -q -o " + body, rc);
  EXPECT_EQ(rc, 0);
  std::string out = run(inspect + " " + block, rc);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("(valid)"), std::string::npos) << out;
  EXPECT_NE(out.find("nodes: 1014, elements: 720"), std::string::npos) << out;
  EXPECT_NE(out.find("skin (visual)"), std::string::npos) << out;
  EXPECT_NE(out.find("press (9)"), std::string::npos) << out;
  out = run(inspect + " " + body, rc);
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("skin (visual)"), std::string::npos) << out;
  EXPECT_NE(out.find("feet ("), std::string::npos) << out;
  // The file holds what the library makes.
  EXPECT_EQ(formats::read_model(body).element_sets,
            make_soft_body_sample_model(0.5425, 4e-3).element_sets);
  EXPECT_EQ(formats::read_model(body).surfaces, make_soft_body_sample_model(0.5425, 4e-3).surfaces);
  // Bad values: exit 1 with the option named; a bad command line: exit 2.
  out = run(tool + " skin-block --dims 0 4 4 -o " + block, rc);
  EXPECT_EQ(rc, 1);
  EXPECT_NE(out.find("--dims"), std::string::npos) << out;
  out = run(tool + " soft-body --voxel-size -1 -o " + body, rc);
  EXPECT_EQ(rc, 1);
  EXPECT_NE(out.find("--voxel-size"), std::string::npos) << out;
  run(tool + " soft-body --no-such-option -o " + body, rc);
  EXPECT_EQ(rc, 2);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sinew::simulator::testing
