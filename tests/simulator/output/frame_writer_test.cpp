// Frames taken with Backend::frame and written by FrameWriter, in the background (the GPU's way)
// or at once (the CPU's), hold exactly the bits of frames written from direct queries
// (displacements(), element_fields()) at the same steps, while the backend steps on between
// taking a frame and writing it; a failing frame is reported by the next push() and nothing after
// it is written.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "engine_test_support.hpp"
#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/simulator/engine/cpu_engine.hpp"
#include "sinew/simulator/output/frame_writer.hpp"
#include "sinew/simulator/output/results_writer.hpp"

namespace sinew::simulator {
namespace {

using testing::BackendTest;
using testing::NamedBackend;
using testing::TempDir;

// One dataset of a results file as doubles.
std::vector<double> read_doubles(const std::string& file, const std::string& path) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  EXPECT_GE(f, 0) << file;
  if (f < 0) return {};
  const hid_t ds = H5Dopen2(f, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(ds, 0) << path;
  std::vector<double> v;
  if (ds >= 0) {
    const hid_t space = H5Dget_space(ds);
    v.resize(std::size_t(H5Sget_simple_extent_npoints(space)));
    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(space);
    H5Dclose(ds);
  }
  H5Fclose(f);
  return v;
}

// The muscle block: fixed at x = 0, its muscle ramping to full activation, every field asked for.
Setup muscle_setup(const formats::Model& model) {
  Setup s;
  s.effects.muscles = true;
  s.effects.damping = true;
  s.damping_alpha = 20;
  s.precision = Precision::float64;
  s.activation = {Curve::ramp(0.05, 1.0)};
  for (const auto& set : model.node_sets)
    if (set.name == "x_min") s.rigid_nodes = set.ids;
  return s;
}

ResultsOptions every_field() {
  ResultsOptions o;
  o.stress = o.jacobian = o.energy_density = o.surfaces = true;
  return o;
}

class FrameWriterTest : public BackendTest<NamedBackend> {};

TEST_P(FrameWriterTest, FramesEqualDirectQueriesInTheBackgroundAndAtOnce) {
  TempDir dir("frames");
  const formats::Model model = testing::small_box(true, true);
  const simulator::Setup setup = muscle_setup(model);
  ASSERT_FALSE(setup.rigid_nodes.empty());
  const std::vector<std::int64_t> gaps = {0, 7, 1, 30, 2, 50};  // steps between frames

  for (const char* sub : {"direct", "background", "at_once"})
    std::filesystem::create_directories(dir / sub);
  // Reference: direct queries, written at once.
  {
    auto b = GetParam().make(model, setup);
    ResultsWriter results(dir / "direct", model, every_field());
    for (auto gap : gaps) {
      b->step(gap);
      results.append_frame(b->time(), b->step_index(), b->displacements(), b->element_fields());
    }
  }
  for (bool background : {true, false}) {
    const std::string out = dir / (background ? "background" : "at_once");
    auto b = GetParam().make(model, setup);
    ResultsWriter results(out, model, every_field());
    FrameWriter writer(results, background, 1.0);
    std::vector<Energies> energies;
    for (auto gap : gaps) {
      b->step(gap);
      Frame f = b->frame(true);
      EXPECT_EQ(f.step, b->step_index());
      energies.push_back(f.energies);
      writer.push(std::move(f));
    }
    writer.finish();
    EXPECT_EQ(writer.frames_written(), std::int64_t(gaps.size()));
    // Energies with the frame are energies() at its step.
    auto c = GetParam().make(model, setup);
    std::int64_t k = 0;
    for (auto gap : gaps) {
      c->step(gap);
      const Energies e = c->energies();
      EXPECT_EQ(e.kinetic, energies[std::size_t(k)].kinetic) << "frame " << k;
      EXPECT_EQ(e.strain, energies[std::size_t(k)].strain) << "frame " << k;
      ++k;
    }
  }
  for (const char* path : {"/frames/time", "/frames/displacement", "/frames/von_mises", "/frames/J",
                           "/frames/energy_density", "/surfaces/skin/positions"}) {
    const auto direct = read_doubles(dir / "direct/results.h5", path);
    ASSERT_FALSE(direct.empty()) << path;
    for (const char* other : {"background", "at_once"}) {
      const auto v = read_doubles(dir / (std::string(other) + "/results.h5"), path);
      ASSERT_EQ(v.size(), direct.size()) << other << path;
      EXPECT_EQ(std::memcmp(v.data(), direct.data(), v.size() * sizeof(double)), 0)
          << path << " written " << other << " differs from direct queries";
    }
  }
  // The muscle did something: J moved away from 1 somewhere.
  const auto j = read_doubles(dir / "direct/results.h5", "/frames/J");
  double most = 0;
  for (double x : j) most = std::max(most, std::abs(x - 1));
  EXPECT_GT(most, 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Backends, FrameWriterTest, ::testing::ValuesIn(testing::every_backend()),
                         testing::backend_name);

// A frame that fails (a full disk, here its fields) is rethrown by the next push or finish, and
// no frame after it is written; the file keeps the frames before it.
TEST(FrameWriter, AnErrorInTheBackgroundIsReportedAndStopsTheWriting) {
  TempDir dir("frames_error");
  const formats::Model model = testing::small_box(true, true);
  auto b = make_cpu_backend(model, muscle_setup(model));
  ResultsWriter results(dir.str(), model, every_field());
  FrameWriter writer(results, true, 1.0, 1);
  writer.push(b->frame(true));
  writer.finish();
  Frame bad = b->frame(true);
  bad.fields = []() -> ElementFields {
    throw IoError("results.h5", "", "no space left on device");
  };
  writer.push(std::move(bad));
  bool reported = false;
  try {
    for (int k = 0; k < 3; ++k) {
      b->step(3);
      writer.push(b->frame(true));
    }
    writer.finish();
  } catch (const IoError& e) {
    reported = true;
    EXPECT_NE(std::string(e.what()).find("no space left"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(reported);
  EXPECT_EQ(writer.frames_written(), 1);
  EXPECT_THROW(writer.finish(), IoError);
  EXPECT_EQ(results.frame_count(), 1);
}

}  // namespace
}  // namespace sinew::simulator
