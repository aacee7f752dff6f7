#pragma once
// Writing a file under its final name in one go: every writer that produces a whole file (model,
// checkpoint, run summary, PNG renders and contact sheets, glTF, PC2, OBJ) writes it to a
// temporary name beside the final one and renames it into place only when the whole file is
// written. A failure (a full disk, an exception of the writer) removes the temporary, so no
// truncated or empty file is ever left under the final name, and no stray temporary either.
//
//   write_atomically(path, [&](const std::string& tmp) { write_png_to(tmp, image); });
//
// The rename is atomic within one file system (the temporary lives in the same folder); there is
// no fsync, so a power cut may still lose the file, but never leaves a half-written one in view.
//
// A signal that ends the process (SIGINT, SIGTERM, SIGHUP) runs no destructor: every tool
// (tool::run) installs remove_temporaries_on_signal(), whose handler unlinks the temporaries being
// written, then ends the process by the same signal (`sinew-render --sequence` and `sinew-export`
// stopped by SIGTERM left their "*.tmp-<pid>" files: issue 33).
#include <cstddef>
#include <functional>
#include <string>

namespace sinew {

// "<path>.tmp-<pid>": the temporary name write_atomically() uses for `path`.
std::string temporary_name(const std::string& path);

// Calls write(tmp) to write the whole file at tmp = temporary_name(path), then renames tmp onto
// path (replacing an existing file). When write throws, tmp is removed and the exception goes on
// unchanged; when the rename fails, tmp is removed and an IoError naming path is thrown.
void write_atomically(const std::string& path,
                      const std::function<void(const std::string&)>& write);

// Writes `text` as the whole file `path` through write_atomically(); IoError naming path (with
// write_failure()'s reason) when it cannot be written.
void write_text_atomically(const std::string& path, const std::string& text);

// The same as a guard, for writers that open and close the file themselves:
//   TemporaryFile out(path);  // write to out.path(), "<path>.tmp-<pid>"
//   ...
//   out.commit();             // renames it onto path (IoError naming path when that fails)
// Without commit() (an exception, an early return) the destructor removes the temporary.
class TemporaryFile {
 public:
  explicit TemporaryFile(std::string path);
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  ~TemporaryFile();
  const std::string& path() const { return tmp_; }
  void commit();

 private:
  std::string final_, tmp_;
  bool committed_ = false;
  int slot_ = -1;  // in the registry the signal handler reads, −1 when untracked
};

// For SIGINT, SIGTERM and SIGHUP whose action is the default (one ignored stays ignored, as under
// nohup or in a background job): a handler that unlinks the temporary of every TemporaryFile not
// yet committed or destroyed (unlink(2): async-signal-safe), restores the default action and
// raises the signal again, so the process ends as it would have (the shell sees the signal).
// Code that installs its own handlers afterwards (sinew-simulate's checkpoint on Ctrl-C, the live
// server) replaces this one and cleans up through the destructors as it returns. Idempotent.
// At most kMaxTrackedTemporaries temporaries are tracked at once; more are written untracked.
inline constexpr std::size_t kMaxTrackedTemporaries = 256;
void remove_temporaries_on_signal();

// The reason a write failed, from errno: "no space left on the device (disk full)" for ENOSPC
// and EDQUOT, else strerror(err).
std::string write_failure(int err);

}  // namespace sinew
