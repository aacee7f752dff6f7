#include "sinew/simulator/engine/model_cache.hpp"

#include <filesystem>

#include "sinew/formats/model_file.hpp"
#include "sinew/formats/sha256.hpp"

namespace sinew::simulator {

std::shared_ptr<const ModelFile> ModelCache::get(const std::string& path) {
  // One slot per file: two spellings of one path share it.
  const std::string key = std::filesystem::absolute(path).lexically_normal().string();
  std::shared_ptr<Slot> slot;
  {
    std::lock_guard lock(mutex_);
    auto& s = slots_[key];
    if (!s) s = std::make_shared<Slot>();
    slot = s;
  }
  // Readers of other files go on meanwhile; readers of this one wait for it.
  std::lock_guard reading(slot->reading);
  std::shared_ptr<const ModelFile> file = slot->file.lock();
  if (!file) {
    auto f = std::make_shared<ModelFile>();
    f->model = formats::read_model(path);
    f->sha256 = formats::sha256_file(path);
    file = std::move(f);
    slot->file = file;
  }
  std::lock_guard lock(mutex_);
  last_ = file;
  return file;
}

}  // namespace sinew::simulator
