#include "sinew/common/input_file.hpp"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "sinew/common/error.hpp"

namespace sinew {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a plain file";
}

}  // namespace

void require_regular_file(const std::filesystem::path& path, const std::string& what) {
  // stat() follows links, so a link to a regular file passes and one to /dev/zero does not.
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw IoError(path.string(), "", "cannot open the " + what + ": " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    throw IoError(path.string(), "",
                  "the " + what + " is " + kind_of(st.st_mode) + ", not a regular file");
  }
}

}  // namespace sinew
