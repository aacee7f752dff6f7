// ModelCache (simulator/engine/model_cache.hpp): each model file read and hashed once, shared across
// threads, errors as the reader's, entries released when no run uses them.
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
#include <thread>
#include <vector>

#include "sim_io_support.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/sha256.hpp"
#include "sinew/simulator/engine/model_cache.hpp"

namespace sinew::simulator {
namespace {

using testing::TempDir;

TEST(ModelCache, ReadsAFileOnceAndSharesItUnderAnySpelling) {
  TempDir dir("model_cache_once");
  const auto path = dir / "box.h5";
  formats::write_model(testing::small_box(true, false, 3, 2, 2), path);
  ModelCache cache;
  const auto a = cache.get(path);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->model.element_count(), 12u);
  EXPECT_EQ(a->model.muscles.size(), 1u);
  EXPECT_EQ(a->sha256, formats::sha256_file(path));
  // The same object again, also through a path with a detour.
  EXPECT_EQ(cache.get(path).get(), a.get());
  EXPECT_EQ(cache.get(dir / "sub/../box.h5").get(), a.get());
}

TEST(ModelCache, ThreadsAskingAtOnceShareOneRead) {
  TempDir dir("model_cache_threads");
  const auto path = dir / "box.h5";
  formats::write_model(testing::small_box(false, false, 6, 6, 6), path);
  ModelCache cache;
  std::vector<std::shared_ptr<const ModelFile>> got(8);
  std::vector<std::thread> threads;
  for (std::size_t k = 0; k < got.size(); ++k)
    threads.emplace_back([&, k] { got[k] = cache.get(path); });
  for (auto& t : threads) t.join();
  for (const auto& g : got) {
    ASSERT_TRUE(g);
    EXPECT_EQ(g.get(), got[0].get());
  }
  EXPECT_EQ(got[0]->model.element_count(), 216u);
}

TEST(ModelCache, ABadFileThrowsTheReadersErrorAtEveryRequestAndIsNotKept) {
  TempDir dir("model_cache_bad");
  const auto path = dir / "box.h5";
  testing::write_file(path, "not an HDF5 file");
  ModelCache cache;
  for (int k = 0; k < 2; ++k) {
    try {
      cache.get(path);
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_EQ(e.file(), path) << e.what();
    }
  }
  // The failure is not remembered: a good file at the path now reads.
  formats::write_model(testing::small_box(), path);
  EXPECT_EQ(cache.get(path)->model.element_count(), 64u);
  EXPECT_THROW(cache.get(dir / "missing.h5"), IoError);
}

TEST(ModelCache, KeepsOnlyTheFilesInUseAndTheLastOne) {
  TempDir dir("model_cache_release");
  const auto a_path = dir / "a.h5", b_path = dir / "b.h5";
  formats::write_model(testing::small_box(), a_path);
  formats::write_model(testing::small_box(false, false, 2, 2, 2), b_path);
  ModelCache cache;
  std::weak_ptr<const ModelFile> a = cache.get(a_path);
  EXPECT_FALSE(a.expired());  // the last one asked for stays
  const auto b = cache.get(b_path);
  EXPECT_TRUE(a.expired());  // a is neither in use nor the last one
  const auto held = cache.get(a_path);
  EXPECT_EQ(cache.get(b_path).get(), b.get());  // b was in use: not read again
  EXPECT_EQ(held->model.element_count(), 64u);
}

}  // namespace
}  // namespace sinew::simulator
