// sinew-mesh-import [--] FILE: reads a mesh file with assimp and writes what it read to stdout as
// the stream of mesh_import.hpp. For sinew's own use: load_mesh runs it as a child process so that
// a file that crashes or hangs assimp ends in an error naming the file (mesh_isolation.hpp). Bad
// content is written as an outcome and the exit status is 0; 2 for a bad command line, 1 when the
// stream cannot be written.
#include <sys/prctl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include "sinew/voxelizer/mesh_import.hpp"

namespace {

bool write_all(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  using sinew::voxelizer::ImportOutcome;
  int first = 1;
  if (argc > 1 && std::strcmp(argv[1], "--") == 0) first = 2;
  if (argc != first + 1) {
    std::fprintf(stderr,
                 "usage: sinew-mesh-import [--] FILE\n"
                 "Reads a mesh with assimp and writes it to stdout for sinew-voxelize "
                 "(docs/voxelizer.md).\n");
    return 2;
  }
  // A crash here is expected on some files and reported by the parent: no core dump of it in the
  // user's folder (RLIMIT_CORE) or to a core_pattern handler (not dumpable).
  const rlimit no_core{0, 0};
  ::setrlimit(RLIMIT_CORE, &no_core);
  ::prctl(PR_SET_DUMPABLE, 0, 0, 0, 0);
  ImportOutcome outcome;
  try {
    outcome = sinew::voxelizer::import_with_assimp(argv[first]);
  } catch (const std::bad_alloc&) {
    outcome = {};
    outcome.kind = ImportOutcome::Kind::io_error;
    outcome.problem = "out of memory reading the mesh";
  } catch (const std::exception& e) {
    outcome = {};
    outcome.kind = ImportOutcome::Kind::format_error;
    outcome.problem = std::string("cannot read the mesh: ") + e.what();
  }
  return write_all(STDOUT_FILENO, sinew::voxelizer::encode_outcome(outcome)) ? 0 : 1;
}
