// Inputs in the wrong place or with values out of scale get a message that says what is wrong
// (issue 20): a model given as results or as a checkpoint, results given as a model, a missing
// model, a voxel size or mass scaling that leaves no usable time step, a NaN in stored results.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <string>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/simulator/engine/checkpoint.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::simulator {
namespace {

using testing::options_for;
using testing::TempDir;
using testing::write_file;

// The error run_scene (or fn) throws, as the message; "" and a failure when none.
template <typename Fn>
std::string error_of(Fn&& fn) {
  try {
    fn();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// A short run of the 4 × 4 × 4 block; returns the output folder.
std::string short_run(const TempDir& dir) {
  formats::write_model(testing::small_box(), dir / "block.h5");
  write_file(dir / "scene.yaml",
             "model: block.h5\neffects: [elasticity, gravity]\nduration: 0.01\n");
  const auto r = run_scene(options_for(dir / "scene.yaml", dir / "out"));
  EXPECT_EQ(r.summary.status, "completed");
  return dir / "out";
}

TEST(ClearMessages, AFileOfTheWrongKindSaysWhatItIs) {
  TempDir dir("wrong_kind");
  const auto out = short_run(dir);
  const auto model = dir / "block.h5";
  auto msg = error_of([&] { postprocess::read_volume_boundary(model); });
  EXPECT_TRUE(contains(msg, "this is a sinew model file, not a sinew results file")) << msg;
  msg = error_of([&] { read_checkpoint(model); });
  EXPECT_TRUE(contains(msg, "this is a sinew model file, not a sinew checkpoint")) << msg;
  msg = error_of([&] { formats::read_model(out + "/results.h5"); });
  EXPECT_TRUE(contains(msg, "this is a sinew results file, not a sinew model file")) << msg;
}

// Runs a scene whose model key is `model` and expects a ConfigError naming the scene and its
// `model` key, with `part` in the message.
void expect_model_key_error(const std::string& dir_name, const std::string& model,
                            const std::string& part) {
  TempDir dir(dir_name);
  write_file(dir / "scene.yaml", "model: " + model + "\neffects: [elasticity]\nduration: 1\n");
  try {
    run_scene(options_for(dir / "scene.yaml", dir / "out"));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), dir / "scene.yaml");
    EXPECT_EQ(e.field(), "model");
    EXPECT_TRUE(contains(e.what(), part)) << e.what();
  }
}

TEST(ClearMessages, AMissingModelNamesTheSceneAndItsModelKey) {
  expect_model_key_error("missing_model", "gone.h5", "gone.h5");
}

TEST(ClearMessages, AModelPathTooLongNamesTheSceneAndItsModelKey) {
  // 5,000 characters: the system refuses the name ("File name too long"); the message says which
  // file and key gave it (issue 33: it was a bare filesystem error).
  expect_model_key_error("long_model", std::string(5000, 'a') + ".h5", "5003 characters");
}

TEST(ClearMessages, AVoxelSizeOrMassScalingOutOfScaleIsNamed) {
  TempDir dir("out_of_scale");
  formats::write_model(testing::small_box(false, false, 2, 2, 2, 1e300), dir / "huge.h5");
  write_file(dir / "scene.yaml", "model: huge.h5\neffects: [elasticity]\nduration: 1\n");
  try {
    run_scene(options_for(dir / "scene.yaml", dir / "out"));
    FAIL();
  } catch (const ConfigError& e) {
    // The model file and its dataset, not the scene (the fuzzer's voxel size of 1e308 m).
    EXPECT_EQ(e.file(), dir / "huge.h5") << e.what();
    EXPECT_EQ(e.field(), "/grid/voxel_size") << e.what();
    EXPECT_TRUE(contains(e.what(), "units")) << e.what();
  }
  formats::write_model(testing::small_box(), dir / "block.h5");
  write_file(dir / "scaled.yaml",
             "model: block.h5\neffects: [elasticity]\nduration: 1\nmass_scaling: 1e300\n");
  try {
    run_scene(options_for(dir / "scaled.yaml", dir / "out"));
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.field(), "mass_scaling") << e.what();
  }
}

TEST(ClearMessages, ANaNInTheResultsNamesTheDatasetThatHoldsIt) {
  TempDir dir("nan_results");
  const auto results = short_run(dir) + "/results.h5";
  {
    const hid_t f = H5Fopen(results.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t ds = H5Dopen2(f, "/frames/displacement", H5P_DEFAULT);
    const hid_t space = H5Dget_space(ds);
    const hsize_t start[3] = {1, 0, 0}, count[3] = {1, 1, 1};
    H5Sselect_hyperslab(space, H5S_SELECT_SET, start, nullptr, count, nullptr);
    const hid_t mem = H5Screate_simple(3, count, nullptr);
    const double nan = std::nan("");
    ASSERT_GE(H5Dwrite(ds, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, &nan), 0);
    H5Sclose(mem);
    H5Sclose(space);
    H5Dclose(ds);
    H5Fclose(f);
  }
  try {
    postprocess::read_volume_boundary(results);
    FAIL();
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "/frames/displacement") << e.what();
    EXPECT_TRUE(contains(e.what(), "node 0 in frame 1")) << e.what();
  }
}

}  // namespace
}  // namespace sinew::simulator
