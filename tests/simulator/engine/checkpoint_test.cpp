// Checkpoints (engine/checkpoint.hpp): the state round-trips bit for bit; other files, an older
// format and a state whose bytes changed on disk are refused, naming the file and the dataset or
// attribute (issue 33: one flipped bit in /u restarted silently with wrong results).
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/simulator/engine/checkpoint.hpp"
#include "sinew/simulator/output/results_writer.hpp"

namespace sinew::simulator {
namespace {

using testing::small_box;
using testing::TempDir;

// A checkpoint of 10 nodes and three sliding bindings with values of every exponent range.
Checkpoint sample_checkpoint() {
  Checkpoint c;
  c.digest = "abc123";
  c.scene_file = "scene.yaml";
  c.model_file = "model.h5";
  c.state.step = 1234;
  c.state.dt = 1e-4 / 3;
  c.state.time = 1234 * c.state.dt;
  c.state.external_work = -0.0;
  c.state.energy_reference = 7.25;
  for (int i = 0; i < 30; ++i) {
    c.state.u.push_back(std::nextafter(1.0 / (i + 1), 2.0));
    c.state.u_prev.push_back(-std::ldexp(1.0, -i * 30) / 3.0);
  }
  c.state.sliding_triangle = {4, -1, 7};
  return c;
}

// Flips bit `bit` of byte `byte` of a contiguous dataset's stored values, in the file's bytes, as
// a bad sector or a bit-rotted copy would.
void flip_stored_bit(const std::string& path, const char* dataset, std::size_t byte, int bit) {
  haddr_t offset = HADDR_UNDEF;
  {
    const hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    const hid_t ds = H5Dopen2(f, dataset, H5P_DEFAULT);
    ASSERT_GE(ds, 0) << dataset;
    offset = H5Dget_offset(ds);
    H5Dclose(ds);
    H5Fclose(f);
  }
  ASSERT_NE(offset, HADDR_UNDEF) << dataset << " is not stored contiguous";
  std::fstream io(path, std::ios::in | std::ios::out | std::ios::binary);
  io.seekg(static_cast<std::streamoff>(offset + byte));
  char c = 0;
  io.get(c);
  c = static_cast<char>(c ^ (1 << bit));
  io.seekp(static_cast<std::streamoff>(offset + byte));
  io.put(c);
  ASSERT_TRUE(io.good());
}

// The FormatError of read_checkpoint(path), or a failure when it reads the file.
FormatError refusal(const std::string& path) {
  try {
    read_checkpoint(path);
  } catch (const FormatError& e) {
    return e;
  }
  ADD_FAILURE() << "read_checkpoint accepted " << path;
  return FormatError(path, "", "accepted");
}

TEST(Checkpoint, RoundTripsTheStateBitForBit) {
  TempDir dir("checkpoint");
  const Checkpoint c = sample_checkpoint();
  write_checkpoint(dir / "c.h5", c);
  const auto r = read_checkpoint(dir / "c.h5");
  EXPECT_EQ(r.digest, "abc123");
  EXPECT_EQ(r.scene_file, "scene.yaml");
  EXPECT_EQ(r.state.step, 1234);
  EXPECT_EQ(r.state.dt, c.state.dt);
  EXPECT_EQ(r.state.time, c.state.time);
  EXPECT_TRUE(std::signbit(r.state.external_work));
  EXPECT_EQ(r.state.energy_reference, 7.25);
  EXPECT_EQ(r.state.u, c.state.u);
  EXPECT_EQ(r.state.u_prev, c.state.u_prev);
  EXPECT_EQ(r.state.sliding_triangle, c.state.sliding_triangle);
  // No temporary left behind.
  std::size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.str()))
    files += entry.is_regular_file();
  EXPECT_EQ(files, 1u);
}

TEST(Checkpoint, RejectsOtherFiles) {
  TempDir dir("checkpoint_bad");
  const auto model = small_box();
  { ResultsWriter w(dir.str(), model, {}); }
  EXPECT_THROW(read_checkpoint(dir / "results.h5"), FormatError);
  testing::write_file(dir / "text.h5", "not hdf5");
  EXPECT_THROW(read_checkpoint(dir / "text.h5"), IoError);
  EXPECT_THROW(read_checkpoint(dir / "missing.h5"), IoError);
}

// /u_prev transposed to 3 × N has the right count and was read as a scrambled state
// (scripts/fuzz_inputs.py); its shape must be that of /u.
TEST(Checkpoint, RefusesAPreviousDisplacementOfAnotherShape) {
  TempDir dir("checkpoint_shape");
  Checkpoint c;
  c.digest = "abc";
  c.scene_file = "scene.yaml";
  c.model_file = "model.h5";
  c.state.dt = 1e-4;
  c.state.u.assign(12, 0.5);
  c.state.u_prev.assign(12, 0.25);
  write_checkpoint(dir / "c.h5", c);
  {
    const auto f = formats::hdf5::open_file(dir / "c.h5", true);
    ASSERT_GE(H5Ldelete(f, "/u_prev", H5P_DEFAULT), 0);
    formats::hdf5::write(f, "/u_prev", {3, 4}, c.state.u_prev.data(), dir / "c.h5");
  }
  try {
    read_checkpoint(dir / "c.h5");
    FAIL() << "expected a FormatError";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.field(), "/u_prev");
  }
}

TEST(Checkpoint, DigestCoversSceneModelAndPrecision) {
  TempDir dir("digest");
  testing::write_file(dir / "a.h5", "model bytes");
  testing::write_file(dir / "b.h5", "other bytes");
  const auto d = run_digest("scene", dir / "a.h5", "double");
  EXPECT_EQ(d.size(), 64u);
  EXPECT_EQ(d, run_digest("scene", dir / "a.h5", "double"));
  EXPECT_NE(d, run_digest("scene ", dir / "a.h5", "double"));
  EXPECT_NE(d, run_digest("scene", dir / "b.h5", "double"));
  EXPECT_NE(d, run_digest("scene", dir / "a.h5", "float"));
}

// One flipped bit in any dataset a restart reads is refused, naming the file and the dataset:
// the low bit of a mantissa (a displacement off by one ulp), a sign, a triangle id.
TEST(Checkpoint, AFlippedBitInTheStateIsRefusedNamingTheDataset) {
  TempDir dir("checkpoint_flip");
  const auto c = sample_checkpoint();
  const std::string path = dir / "c.h5";
  struct Flip {
    const char* dataset;
    std::size_t byte;
    int bit;
  };
  for (const Flip flip : {Flip{"/u", 0, 0}, Flip{"/u", 8 * 29 + 7, 7}, Flip{"/u_prev", 8 * 3, 2},
                          Flip{"/sliding_triangle", 4, 0}}) {
    write_checkpoint(path, c);
    ASSERT_NO_THROW(read_checkpoint(path));
    flip_stored_bit(path, flip.dataset, flip.byte, flip.bit);
    const auto e = refusal(path);
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), flip.dataset);
    EXPECT_NE(e.problem().find("the checkpoint is damaged"), std::string::npos) << e.what();
  }
}

// A root attribute changed after writing (the step of issue 33's 1e15 case, the time, the work)
// is refused against the root digest, state_sha256.
TEST(Checkpoint, AChangedRootAttributeIsRefused) {
  TempDir dir("checkpoint_attr");
  const std::string path = dir / "c.h5";
  const auto change = [&](const char* name, auto value) {
    write_checkpoint(path, sample_checkpoint());
    {
      const auto f = formats::hdf5::open_file(path, true);
      formats::hdf5::set_attribute(f, name, value, path);
    }
    const auto e = refusal(path);
    EXPECT_EQ(e.field(), "state_sha256") << name;
  };
  change("step", std::int64_t{1'000'000'000'000'000});
  change("time", 0.5);
  change("external_work", 1e-300);
  change("scene_file", std::string("other.yaml"));
}

// A checkpoint of format 1 (no state digests) is refused with a message saying why, not read.
TEST(Checkpoint, RefusesTheOlderFormatWithoutStateDigests) {
  TempDir dir("checkpoint_v1");
  const std::string path = dir / "c.h5";
  write_checkpoint(path, sample_checkpoint());
  {
    const auto f = formats::hdf5::open_file(path, true);
    formats::hdf5::set_attribute(f, "format_version", std::int64_t{1}, path);
  }
  const auto e = refusal(path);
  EXPECT_EQ(e.field(), "format_version");
  EXPECT_NE(e.problem().find("older sinew"), std::string::npos) << e.what();
  EXPECT_NE(e.problem().find("rerun the scene from the start"), std::string::npos) << e.what();
}

}  // namespace
}  // namespace sinew::simulator
