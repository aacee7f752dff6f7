// Fuzz target as a bounded mutation loop: small valid inputs (a model, a results file and a
// checkpoint written by sinew, a scene and a spec text) are mutated at random and fed, in this
// process, to the readers the tools use. Every case must end in the reader's result or a typed
// sinew error (FormatError, ConfigError, IoError, ...): a crash kills the test, an untyped
// exception or a case slower than the case limit (5 s) fails it. docs/development.md, "Fuzzing", says how to
// run longer campaigns (SINEW_FUZZ_SCALE, SINEW_FUZZ_SEED).
//
// Each case is written to a file before it is read (the readers take paths), so after a crash the
// case that crashed is the file named "case.*" in the folder printed at the start.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <spdlog/spdlog.h>
#include "../formats/test_models.hpp"
#include "../simulator/sim_io_support.hpp"

#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/summary.hpp"
#include "sinew/postprocess/results_reader.hpp"
#include "sinew/simulator/engine/checkpoint.hpp"
#include "sinew/simulator/output/results_writer.hpp"
#include "sinew/simulator/run/scene.hpp"
#ifdef SINEW_FUZZ_WITH_VOXELIZER
#include "sinew/voxelizer/spec.hpp"
#endif

namespace sinew {
namespace {

namespace fs = std::filesystem;
using Bytes = std::string;
using formats::hdf5::Handle;

// No single case may take longer; a case that never returns is caught by the alarm below. Model
// case 24952 of seed 1 once took 0.1 to 2 s in the sequence, and over 5 s on a loaded machine:
// HDF5 re-read a damaged metadata block with sleeps between its read attempts; files are now
// opened with one attempt (hdf5_file.cpp, read_access), and the slowest case takes 0.16 s.
// SINEW_FUZZ_CASE_LIMIT (s) sets another limit, e.g. a low one to collect the slowest cases of a
// campaign (each slow case is saved beside case.* as case.*.slow-<i>, up to 5 per kind).
double case_limit() {
  const char* s = std::getenv("SINEW_FUZZ_CASE_LIMIT");
  const double v = s ? std::atof(s) : 0.0;
  return v > 0 ? v : 5.0;
}

// SINEW_FUZZ_SCALE multiplies every kind's case count (default 1: 100,000 cases in all);
// SINEW_FUZZ_SEED picks another sequence of mutations (default 1); SINEW_FUZZ_DIR where the case
// files go (default /dev/shm where it exists, else the temp folder).
std::size_t scaled(std::size_t cases) {
  const char* s = std::getenv("SINEW_FUZZ_SCALE");
  const double k = s ? std::atof(s) : 1.0;
  return static_cast<std::size_t>(static_cast<double>(cases) * (k > 0 ? k : 1.0));
}
std::uint64_t seed() {
  const char* s = std::getenv("SINEW_FUZZ_SEED");
  return s ? std::strtoull(s, nullptr, 10) : 1;
}

using simulator::testing::read_file;  // both binary
using simulator::testing::write_file;

class Mutator {
 public:
  explicit Mutator(std::uint64_t s) : rng_(s) {}
  std::size_t below(std::size_t n) { return n == 0 ? 0 : rng_() % n; }

  // One to four changes of a binary file: bit flips, random and boundary bytes, boundary values
  // over 2, 4 or 8 bytes (sizes, addresses and counts in HDF5 metadata), a block copied from
  // elsewhere, rarely a truncation.
  Bytes binary(Bytes b) {
    static const unsigned char kBytes[] = {0x00, 0xff, 0x7f, 0x80, 0x01, 0x04, 0x85, 0x10};
    static const std::uint64_t kWords[] = {
        0,    1,     0xff,    0x7fffffff, 0xffffffff, 0xffffffffffffffff, 0x8000000000000000,
        4096, 65536, 1u << 31};
    const auto changes = 1 + below(4);
    for (std::size_t c = 0; c < changes && !b.empty(); ++c) {
      const auto at = below(b.size());
      switch (below(12)) {
        case 0:
        case 1:
        case 2:
          b[at] = static_cast<char>(b[at] ^ (1 << below(8)));
          break;
        case 3:
        case 4:
          b[at] = static_cast<char>(below(256));
          break;
        case 5:
        case 6:
          b[at] = static_cast<char>(kBytes[below(sizeof kBytes)]);
          break;
        case 7:
        case 8: {
          const std::size_t width = std::size_t{2} << below(3);
          const auto w = kWords[below(sizeof kWords / sizeof kWords[0])];
          for (std::size_t k = 0; k < width && at + k < b.size(); ++k) {
            b[at + k] = static_cast<char>((w >> (8 * k)) & 0xff);
          }
          break;
        }
        case 9:
        case 10: {
          const auto from = below(b.size());
          const auto n = std::min({1 + below(64), b.size() - from, b.size() - at});
          b.replace(at, n, b.substr(from, n));
          break;
        }
        default:
          if (below(4) == 0) b.resize(at);
      }
    }
    return b;
  }

  // One to four changes of a YAML text: characters replaced, ranges deleted or duplicated, tokens
  // that YAML or the schema treat specially inserted (anchors, tags, flow brackets, huge, tiny and
  // non-finite numbers, long strings).
  Bytes text(Bytes t) {
    static const char* kTokens[] = {"1e308",
                                    "-1",
                                    "nan",
                                    ".nan",
                                    ".inf",
                                    "-.inf",
                                    "0",
                                    "1e-300",
                                    "2e14",
                                    "1e30",
                                    "1e-15",
                                    "[",
                                    "]",
                                    "{",
                                    "}",
                                    ": ",
                                    "- ",
                                    "&a ",
                                    "*a",
                                    "!!binary ",
                                    "!!str ",
                                    "'",
                                    "\"",
                                    "\n",
                                    "\n  ",
                                    "#",
                                    "~",
                                    "null",
                                    "true",
                                    "99999999999999999999",
                                    "-0",
                                    "0x10",
                                    "<<: *a",
                                    "? ",
                                    "|\n",
                                    ">-\n",
                                    "\t",
                                    "\\",
                                    "%YAML 1.2\n---\n",
                                    "...\n",
                                    "\xc3\x28",
                                    "\xff",
                                    "aaaaaaaaaaaaaaaaaaaa"};
    const auto changes = 1 + below(4);
    for (std::size_t c = 0; c < changes; ++c) {
      const auto at = below(t.size() + 1);
      switch (below(6)) {
        case 0:
          if (at < t.size()) t[at] = static_cast<char>(32 + below(95));
          break;
        case 1:
          t.erase(at, below(16) + 1);
          break;
        case 2: {
          const auto from = below(t.size() + 1);
          t.insert(at, t.substr(from, below(48) + 1));
          break;
        }
        case 3:
        case 4:
          t.insert(at, kTokens[below(sizeof kTokens / sizeof kTokens[0])]);
          break;
        default:
          if (at < t.size()) t[at] = static_cast<char>(t[at] ^ (1 << below(8)));
      }
    }
    return t;
  }

 private:
  std::mt19937_64 rng_;
};

// A campaign over one kind of input: `cases` mutations of the seeds, each written to `file` and
// handed to `read`. Typed sinew errors are expected; anything else is a failure.
struct Campaign {
  std::string kind;
  std::vector<Bytes> seeds;
  bool binary = true;
  std::string file;
  std::function<void(const std::string&)> read;
};

// A case that never returns (HDF5 looping on a damaged heap did once) would hold the suite until
// ctest's timeout: an alarm ends the process after kHangLimit, naming the case file to rerun.
constexpr unsigned kHangLimit = 60;  // s
std::string hung_case_message;
extern "C" void on_hang(int) {
  const auto n = ::write(2, hung_case_message.data(), hung_case_message.size());
  (void)n;
  ::_exit(124);
}

void run(const Campaign& c, std::size_t cases) {
  hung_case_message = "FAILED: a " + c.kind + " case hung for " + std::to_string(kHangLimit) +
                      " s; its input is " + c.file + "\n";
  std::signal(SIGALRM, on_hang);
  Mutator m(seed() * 1000003 + std::hash<std::string>{}(c.kind));
  std::size_t rejected = 0, accepted = 0, untyped = 0, slow = 0, open_after = 0;
  double slowest = 0;
  std::size_t slowest_case = 0;
  const auto start = std::chrono::steady_clock::now();
  std::cout << c.kind << ": " << cases << " cases, each written to " << c.file << " first"
            << std::endl;
  for (std::size_t i = 0; i < cases; ++i) {
    const auto& base = c.seeds[m.below(c.seeds.size())];
    const auto input = c.binary ? m.binary(base) : m.text(base);
    write_file(c.file, input);
    if (std::getenv("SINEW_FUZZ_KEEP_INPUT")) write_file(c.file + ".input", input);
    const auto t0 = std::chrono::steady_clock::now();
    ::alarm(kHangLimit);
    try {
      c.read(c.file);
      ++accepted;
    } catch (const Error&) {
      ++rejected;
    } catch (const std::exception& e) {
      if (untyped++ < 5) ADD_FAILURE() << c.kind << " case " << i << ": untyped " << e.what();
    }
    ::alarm(0);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (dt > slowest) {
      slowest = dt;
      slowest_case = i;
    }
    if (dt > case_limit() && slow++ < 5) {
      ADD_FAILURE() << c.kind << " case " << i << " took " << dt << " s";
      write_file(c.file + ".slow-" + std::to_string(i), input);
    }
    // Every reader closes what it opened, also on error: an HDF5 file left open would leak and
    // could stand in for the next case's file.
    if (H5Fget_obj_count(H5F_OBJ_ALL, H5F_OBJ_ALL) != 0 && open_after++ < 5) {
      ADD_FAILURE() << c.kind << " case " << i << " left HDF5 objects open";
      write_file(c.file + ".leak-" + std::to_string(i), input);
    }
  }
  const double total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << c.kind << ": " << cases << " cases in " << total << " s: " << accepted << " read, "
            << rejected << " rejected with a typed error, " << untyped
            << " untyped errors; slowest case " << slowest_case << " " << slowest * 1e3 << " ms\n";
  EXPECT_EQ(untyped, 0u);
  EXPECT_EQ(slow, 0u);
  EXPECT_EQ(open_after, 0u);
  EXPECT_GT(rejected, 0u) << "the mutations never broke the input: the campaign tests nothing";
}

class Fuzz : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // The cases are files: on a RAM disk (SINEW_FUZZ_DIR, else /dev/shm where it exists) they
    // cost a third of what they cost on a busy disk.
    const char* chosen = std::getenv("SINEW_FUZZ_DIR");
    std::error_code ec;
    if (!chosen && fs::is_directory("/dev/shm", ec) && ::access("/dev/shm", W_OK) == 0) {
      chosen = "/dev/shm";
    }
    if (chosen) ::setenv("TMPDIR", chosen, 1);
    if (std::getenv("SINEW_FUZZ_NO_FREE_LISTS")) H5set_free_list_limits(0, 0, 0, 0, 0, 0);
    spdlog::set_level(spdlog::level::off);  // the readers' warnings about odd but valid files
    dir_ = new simulator::testing::TempDir("fuzz");
    std::cout << "cases go to " << dir_->str() << std::endl;
  }
  static void TearDownTestSuite() {
    // After a failure the folder stays, with the slow or leaking cases saved beside case.*.
    if (::testing::UnitTest::GetInstance()->failed_test_count() > 0) {
      std::cout << "cases kept in " << dir_->str() << std::endl;
    } else {
      delete dir_;
    }
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return *dir_ / name; }
  static simulator::testing::TempDir* dir_;
};
simulator::testing::TempDir* Fuzz::dir_ = nullptr;

simulator::ResultsOptions every_field() {
  simulator::ResultsOptions o;
  o.stress = o.jacobian = o.energy_density = o.surfaces = true;
  o.model_file = "model.h5";
  o.scene_file = "scene.yaml";
  return o;
}

Bytes source_text(const std::string& relative) {
  return read_file(std::string(SINEW_SOURCE_DIR) + "/" + relative);
}

// A copy of `from` in HDF5's earliest file format (version 1 object headers, no checksums), as
// sinew wrote files before the 1.8+ format and other tools still write them by default.
void copy_to_earliest_format(const std::string& from, const std::string& to) {
  Handle src(H5Fopen(from.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  Handle dst(H5Fcreate(to.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
  ASSERT_TRUE(src.valid() && dst.valid());
  struct Pair {
    hid_t src, dst;
  } pair{src, dst};
  H5Literate(
      src, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        const auto* p = static_cast<Pair*>(data);
        return H5Ocopy(p->src, name, p->dst, name, H5P_DEFAULT, H5P_DEFAULT);
      },
      &pair);
  H5Aiterate2(
      src, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t loc, const char* name, const H5A_info_t* info, void* data) -> herr_t {
        const auto* p = static_cast<Pair*>(data);
        Handle a(H5Aopen(loc, name, H5P_DEFAULT), H5Aclose);
        Handle type(H5Aget_type(a), H5Tclose);
        Handle space(H5Aget_space(a), H5Sclose);
        std::vector<char> value(std::max<std::size_t>(info->data_size, H5Tget_size(type)) + 64);
        if (H5Aread(a, type, value.data()) < 0) return -1;
        Handle b(H5Acreate2(p->dst, name, type, space, H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
        const herr_t written = H5Awrite(b, type, value.data());
        H5Dvlen_reclaim(type, space, H5P_DEFAULT, value.data());
        return written;
      },
      &pair);
}

TEST_F(Fuzz, ModelFiles) {
  // The every-feature model (layers, muscles, sliding, a visual surface, named sets, provenance),
  // a 2 × 2 × 2 box with a muscle and a visual surface, and that box in the earliest format.
  formats::write_model(formats::testing::every_feature_model(), path("every.h5"));
  formats::write_model(simulator::testing::small_box(true, true, 2, 2, 2), path("box.h5"));
  copy_to_earliest_format(path("box.h5"), path("old.h5"));
  ASSERT_NO_THROW(formats::read_model(path("old.h5")));
  run({"model",
       {read_file(path("every.h5")), read_file(path("box.h5")), read_file(path("old.h5"))},
       true,
       path("case.model.h5"),
       [](const std::string& p) {
         // As sinew-inspect: read (and validate), then summarize what was accepted.
         const auto summary = formats::summarize(formats::read_model(p));
         formats::summary_text(summary);
         formats::summary_json(summary);
       }},
      scaled(25000));
}

TEST_F(Fuzz, ResultsFiles) {
  // Three frames of a 2 × 2 × 2 box with a muscle and the visual surface "skin", every field;
  // read as sinew-render and sinew-export read it, and reopened as a restart reopens it.
  const auto model = simulator::testing::small_box(true, true, 2, 2, 2);
  const auto dir = path("results");
  fs::create_directories(dir);
  {
    simulator::ResultsWriter w(dir, model, every_field());
    simulator::ElementFields f;
    const auto e = model.element_count();
    f.von_mises.assign(e, 1.0);
    f.jacobian.assign(e, 1.0);
    f.energy_density.assign(e, 2.0);
    for (int k = 0; k < 3; ++k) {
      std::vector<double> u(3 * model.node_count(), 1e-4 * k);
      w.append_frame(0.01 * k, 10 * k, u, f);
    }
  }
  const auto seed_bytes = read_file(dir + "/results.h5");
  const auto case_dir = path("case_results");
  fs::create_directories(case_dir);
  std::size_t n = 0;
  run({"results",
       {seed_bytes},
       true,
       case_dir + "/results.h5",
       [&](const std::string& p) {
         postprocess::list_surfaces(p);
         switch (n++ % 4) {
           case 0:
             postprocess::read_surface(p, "skin");
             break;
           case 1:
             postprocess::read_volume_boundary(p);
             break;
           case 2:
             simulator::ResultsWriter::resume(case_dir, model, every_field(), 10);
             break;
           default:
             postprocess::read_surface(p);
         }
       }},
      scaled(25000));
}

TEST_F(Fuzz, CheckpointFiles) {
  simulator::Checkpoint c;
  c.state.step = 42;
  c.state.time = 4.2e-3;
  c.state.dt = 1e-4;
  c.state.u.assign(27 * 3, 1e-5);
  c.state.u_prev.assign(27 * 3, 2e-5);
  c.state.sliding_triangle = {3, -1, 0};
  c.digest = std::string(64, 'a');
  c.scene_file = "scene.yaml";
  c.model_file = "model.h5";
  simulator::write_checkpoint(path("checkpoint.h5"), c);
  run({"checkpoint",
       {read_file(path("checkpoint.h5"))},
       true,
       path("case.checkpoint.h5"),
       [](const std::string& p) { simulator::read_checkpoint(p); }},
      scaled(20000));
}

TEST_F(Fuzz, SceneTexts) {
  // The sample scenes, parsed and then resolved against a box that has their sets and muscle.
  const auto model = simulator::testing::small_box(true, true, 2, 2, 2);
  std::vector<Bytes> seeds;
  for (const char* s :
       {"box_compression.yaml", "muscle_block.yaml", "skin_block_press.yaml", "brow_raise.yaml"}) {
    seeds.push_back(source_text(std::string("data/scenes/") + s));
  }
  const auto dir = path("");
  std::size_t cases = scaled(15000);
#ifndef SINEW_FUZZ_WITH_VOXELIZER
  cases += scaled(15000);  // the spec texts' share, so that the suite still runs 100,000 cases
#endif
  run({"scene", seeds, false, path("case.scene.yaml"),
       [&](const std::string& p) {
         const auto scene = simulator::parse_scene_text(read_file(p), p, dir);
         simulator::resolve_scene(scene, model);
       }},
      cases);
}

#ifdef SINEW_FUZZ_WITH_VOXELIZER
TEST_F(Fuzz, SpecTexts) {
  std::vector<Bytes> seeds;
  for (const char* s : {"layered_box.yaml", "forehead_1mm.yaml", "concentric_spheres.yaml"}) {
    seeds.push_back(source_text(std::string("data/specs/") + s));
  }
  run({"spec", seeds, false, path("case.spec.yaml"),
       [](const std::string& p) { voxelizer::parse_spec(read_file(p), p); }},
      scaled(15000));
}
#endif

}  // namespace
}  // namespace sinew
