#include "sinew/common/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

#include "sinew/common/error.hpp"

namespace sinew {

std::string temporary_name(const std::string& path) {
  // The pid keeps two processes writing the same output from sharing a temporary.
  return path + ".tmp-" + std::to_string(static_cast<long>(::getpid()));
}

TemporaryFile::TemporaryFile(std::string path)
    : final_(std::move(path)), tmp_(temporary_name(final_)) {}

TemporaryFile::~TemporaryFile() {
  if (!committed_) std::remove(tmp_.c_str());
}

void TemporaryFile::commit() {
  if (std::rename(tmp_.c_str(), final_.c_str()) != 0) {
    throw IoError(final_, "",
                  "cannot rename the temporary file into place: " + write_failure(errno));
  }
  committed_ = true;
}

void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write) {
  TemporaryFile out(path);
  write(out.path());
  out.commit();
}

void write_text_atomically(const std::string& path, const std::string& text) {
  write_atomically(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw IoError(path, "", "cannot open for writing: " + write_failure(errno));
    const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
    const int write_err = errno;
    // fclose flushes the stdio buffer: a full disk often shows only here.
    const bool closed = std::fclose(f) == 0;
    if (!written || !closed) {
      throw IoError(path, "", "cannot write: " + write_failure(written ? errno : write_err));
    }
  });
}

std::string write_failure(int err) {
  if (err == ENOSPC || err == EDQUOT) return "no space left on the device (disk full)";
  return std::strerror(err);
}

}  // namespace sinew
