#pragma once
// Model files read once per process and shared by the runs that use them. sinew-sweep runs many
// scenes over one model (or a few): each run would otherwise read the file again, under formats'
// process-wide HDF5 lock (hdf5_file.hpp), which serialises the runs' set-ups, and hash it again for
// its checkpoint digest (run_digest). A formats::Model is immutable once read; runs and their
// engines only read it (the engines copy what they need), from any thread.
//
// Memory: an entry lives while a run uses it, and the most recently requested file is kept besides,
// so a sweep over one model reads it once and a resolution study holds at most the models of its
// runs in flight plus one.
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "sinew/formats/model.hpp"

namespace sinew::simulator {

struct ModelFile {
  formats::Model model;
  std::string sha256;  // formats::sha256_file of the file (hex): the model's part of run_digest
};

class ModelCache {
 public:
  // The model file at `path`, read (formats::read_model) and hashed at the first request; later
  // requests, from any thread, share it, and a request while another thread reads the same file
  // waits for that read. A file that fails to read is not kept: every request throws the reader's
  // own error (IoError / FormatError naming the file).
  std::shared_ptr<const ModelFile> get(const std::string& path);

 private:
  struct Slot {
    std::mutex reading;
    std::weak_ptr<const ModelFile> file;
  };
  std::mutex mutex_;
  std::map<std::string, std::shared_ptr<Slot>> slots_;
  std::shared_ptr<const ModelFile> last_;  // the most recent request's file, kept
};

}  // namespace sinew::simulator
