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
};

// The reason a write failed, from errno: "no space left on the device (disk full)" for ENOSPC
// and EDQUOT, else strerror(err).
std::string write_failure(int err);

}  // namespace sinew
