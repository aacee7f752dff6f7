// Several threads using the formats layer at once, each on its own files: what sinew-sweep
// --concurrent K and the simulator's background frame writer do. Every HDF5 call goes through
// formats' one lock (hdf5_file.hpp, library_mutex()). These tests pass on a thread-safe HDF5 build
// (Debian's) with or without that lock, since HDF5 then serialises itself; on a serial, not
// thread-safe build (Ubuntu's libhdf5-dev 1.10, the GPU machine's) they are the ones that crash or
// mix up contents and error messages without it. Checked by linking these tests against Debian's
// libhdf5_openmpi.so.103 (1.10.8, "Threadsafety: no", H5is_library_threadsafe 0): with the lock
// taken out, ModelFilesWrittenAndReadInEightThreads segfaulted in 3 runs of 3; with it, 5 of 5
// passed.
#include <atomic>
#include <cstdint>
#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/model_file.hpp"
#include "test_models.hpp"

namespace sinew::formats {
namespace {

using testing::every_feature_model;
using testing::temp_path;

constexpr int kThreads = 8;
constexpr int kIterations = 20;

// Runs body(thread, iteration) for every iteration in each of kThreads threads at once (started
// together), and returns the failures as text: an exception escaping a thread would terminate.
std::vector<std::string> in_threads(const std::function<void(int, int)>& body) {
  std::vector<std::string> failures(kThreads);
  std::atomic<int> ready{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      ++ready;
      while (ready.load() < kThreads) std::this_thread::yield();
      try {
        for (int i = 0; i < kIterations; ++i) body(t, i);
      } catch (const std::exception& e) {
        failures[static_cast<std::size_t>(t)] = e.what();
      }
    });
  }
  for (auto& th : threads) th.join();
  std::vector<std::string> out;
  for (int t = 0; t < kThreads; ++t) {
    const auto& f = failures[static_cast<std::size_t>(t)];
    if (!f.empty()) out.push_back("thread " + std::to_string(t) + ": " + f);
  }
  return out;
}

// A model whose contents tell the thread and the iteration apart (a density, a name, a value
// per element, the provenance), so a file read back with another thread's data fails the check.
Model model_of(int thread, int iteration) {
  Model m = every_feature_model();
  const int tag = thread * 1000 + iteration;
  m.materials[0].density = 900.0 + tag;
  m.muscles[1].name = "frontalis_" + std::to_string(tag);
  for (std::size_t k = 0; k < m.material_fractions.size(); ++k)
    m.material_fractions[k] *= 1.0 - 1e-6 * double((tag + int(k)) % 97);
  m.provenance.parameters_json = "{\"tag\": " + std::to_string(tag) + "}";
  return m;
}

TEST(Hdf5Threads, ModelFilesWrittenAndReadInEightThreads) {
  std::vector<std::string> paths;
  for (int t = 0; t < kThreads; ++t) paths.push_back(temp_path(std::to_string(t) + ".h5"));
  std::atomic<int> checked{0};
  const auto failures = in_threads([&](int t, int i) {
    const auto& path = paths[static_cast<std::size_t>(t)];
    const Model written = model_of(t, i);
    write_model(written, path);
    const Model read = read_model(path);
    if (!(read == written)) {
      throw std::runtime_error(path + ": iteration " + std::to_string(i) + " read back different");
    }
    ++checked;
  });
  EXPECT_TRUE(failures.empty()) << ::testing::PrintToString(failures);
  EXPECT_EQ(checked.load(), kThreads * kIterations);
}

// Results-like files: an extendible series grown frame by frame and flushed, a frame view, string
// datasets and attributes (the variable-length ones pass through the global heap check), read
// back after the close; and a missing dataset and a non-HDF5 file, whose errors must name this
// thread's own file (HDF5's error stack is process-wide on a serial build).
TEST(Hdf5Threads, ResultsLikeFilesAndErrorsInEightThreads) {
  using namespace hdf5;
  std::vector<std::string> paths, texts;
  for (int t = 0; t < kThreads; ++t) {
    paths.push_back(temp_path("results_" + std::to_string(t) + ".h5"));
    texts.push_back(temp_path("text_" + std::to_string(t) + ".h5"));
    std::ofstream(texts.back()) << "not HDF5, thread " << t << "\n";
  }
  constexpr int kFrames = 5;
  std::atomic<int> checked{0};
  const auto failures = in_threads([&](int t, int i) {
    const auto& path = paths[static_cast<std::size_t>(t)];
    const double tag = t * 1000 + i;
    const std::string label = "run " + std::to_string(t) + "/" + std::to_string(i);
    {
      auto f = create_file(path);
      create_group(f, "/frames", path, true);
      auto series = create_series<double>(f, "/frames/u", {4, 3}, path);
      for (int k = 0; k < kFrames; ++k) {
        std::vector<double> frame(12);
        for (std::size_t j = 0; j < frame.size(); ++j) frame[j] = tag + k + 1e-3 * double(j);
        append<double>(series, hsize_t(k), frame.data(), path, "/frames/u");
        flush(f, path);
      }
      create_frame_view(f, "/views/last", "/frames/u", kFrames - 1, path);
      write_strings(f, "/names", {label, "skin", ""}, path);
      set_attribute(f, "format", "sinew-results-like", path, StringKind::variable);
      set_attribute(f, "label", label, path);
      set_attribute(f, "tag", tag, path);
      close_file(f, path);
    }
    auto f = open_checked(path);
    const auto u = read<double>(f, "/frames/u", path, 12 * kFrames);
    for (int k = 0; k < kFrames; ++k) {
      for (int j = 0; j < 12; ++j) {
        if (u[std::size_t(12 * k + j)] != tag + k + 1e-3 * j)
          throw std::runtime_error(path + ": a frame value differs, " + label);
      }
    }
    const auto last = read<double>(f, "/views/last", path, 12);
    if (last.front() != tag + kFrames - 1) throw std::runtime_error(path + ": the view differs");
    if (read_strings(f, "/names", path) != std::vector<std::string>{label, "skin", ""} ||
        string_attribute(f, "format", path) != "sinew-results-like" ||
        string_attribute(f, "label", path) != label || double_attribute(f, "tag", path) != tag ||
        members(f, "/", path) != std::vector<std::string>{"frames", "names", "views"}) {
      throw std::runtime_error(path + ": strings or attributes differ, " + label);
    }
    try {
      read_array<double>(f, "/frames/missing", path);
      throw std::runtime_error(path + ": a missing dataset was read");
    } catch (const FormatError& e) {
      if (std::string(e.what()).find(path) == std::string::npos)
        throw std::runtime_error(std::string("a missing dataset's error names another file: ") +
                                 e.what());
    }
    const auto& text = texts[static_cast<std::size_t>(t)];
    try {
      open_file(text, false);
      throw std::runtime_error(text + ": a text file opened as HDF5");
    } catch (const IoError& e) {
      if (std::string(e.what()).find(text) == std::string::npos)
        throw std::runtime_error(std::string("a text file's error names another file: ") +
                                 e.what());
    }
    ++checked;
  });
  EXPECT_TRUE(failures.empty()) << ::testing::PrintToString(failures);
  EXPECT_EQ(checked.load(), kThreads * kIterations);
}

// HDF5's automatic error printing is off in every thread, not just the first one to call
// (a thread-safe build keeps that setting per thread): a failed open in a fresh thread prints
// nothing, it is one exception.
TEST(Hdf5Threads, NoHdf5ErrorPrintingInOtherThreads) {
  const auto text = temp_path("text.h5");
  std::ofstream(text) << "not HDF5\n";
  EXPECT_THROW(hdf5::open_file(text, false), IoError);  // this thread first
  ::testing::internal::CaptureStderr();
  std::string failure;
  std::thread([&] {
    try {
      hdf5::open_file(text, false);
      failure = "a text file opened as HDF5";
    } catch (const IoError&) {
    }
  }).join();
  const std::string printed = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(failure, "");
  EXPECT_EQ(printed, "");
}

}  // namespace
}  // namespace sinew::formats
