#include "sinew/common/atomic_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <utility>

#include "sinew/common/error.hpp"

namespace sinew {

namespace {

// The temporaries being written, for the signal handler: lock-free atomics are all a handler may
// touch. A slot holds the c_str() of a live TemporaryFile's name (a std::string that is not
// modified while registered) and is cleared before that string is destroyed.
std::atomic<const char*> g_temporaries[kMaxTrackedTemporaries];
static_assert(std::atomic<const char*>::is_always_lock_free);

int track(const char* path) {
  for (std::size_t i = 0; i < kMaxTrackedTemporaries; ++i) {
    const char* empty = nullptr;
    if (g_temporaries[i].compare_exchange_strong(empty, path)) return static_cast<int>(i);
  }
  return -1;
}

void untrack(int slot) {
  if (slot >= 0) g_temporaries[slot].store(nullptr);
}

extern "C" void remove_temporaries_and_reraise(int sig) {
  const int saved = errno;
  for (auto& slot : g_temporaries) {
    if (const char* path = slot.load()) ::unlink(path);
  }
  // The default action, delivered once this handler returns (the signal is blocked inside it).
  std::signal(sig, SIG_DFL);
  std::raise(sig);
  errno = saved;
}

}  // namespace

std::string temporary_name(const std::string& path) {
  // The pid keeps two processes writing the same output from sharing a temporary.
  return path + ".tmp-" + std::to_string(static_cast<long>(::getpid()));
}

TemporaryFile::TemporaryFile(std::string path)
    : final_(std::move(path)), tmp_(temporary_name(final_)), slot_(track(tmp_.c_str())) {}

TemporaryFile::~TemporaryFile() {
  if (!committed_) std::remove(tmp_.c_str());
  untrack(slot_);
}

void TemporaryFile::commit() {
  if (std::rename(tmp_.c_str(), final_.c_str()) != 0) {
    throw IoError(final_, "",
                  "cannot rename the temporary file into place: " + write_failure(errno));
  }
  // After the rename: a signal in between unlinks a name that is gone, which does nothing.
  committed_ = true;
  untrack(slot_);
  slot_ = -1;
}

void remove_temporaries_on_signal() {
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction current {};
    if (::sigaction(sig, nullptr, &current) != 0 || current.sa_handler != SIG_DFL) continue;
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_reraise;
    sigemptyset(&action.sa_mask);
    ::sigaction(sig, &action, nullptr);
  }
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
