#include "sinew/voxelizer/mesh_isolation.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

#include "sinew/common/error.hpp"

extern char** environ;

namespace sinew::voxelizer {
namespace {

constexpr const char* kHelperName = "sinew-mesh-import";

using Clock = std::chrono::steady_clock;

double default_timeout(const std::filesystem::path& file) {
  if (const char* env = std::getenv("SINEW_MESH_IMPORT_TIMEOUT")) {
    char* end = nullptr;
    const double s = std::strtod(env, &end);
    if (end != env && *end == '\0' && s > 0 && std::isfinite(s)) return s;
  }
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  return 30.0 + (ec ? 0.0 : static_cast<double>(size) / (1 << 20));
}

// Closes a descriptor once (on every path out of import_mesh_isolated).
struct Fd {
  int fd = -1;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// The child's end: killed and reaped if the parent leaves early (an exception, the deadline).
struct Child {
  pid_t pid = -1;
  ~Child() {
    if (pid > 0) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
      }
    }
  }
};

std::string signal_text(int sig) {
  const char* name = ::strsignal(sig);
  return "signal " + std::to_string(sig) + (name ? std::string(": ") + name : std::string());
}

}  // namespace

std::filesystem::path find_mesh_import_helper() {
  std::vector<std::filesystem::path> tried;
  if (const char* env = std::getenv("SINEW_MESH_IMPORT"); env && *env) {
    // Named on purpose: no search past it, so a wrong value is reported, not hidden.
    if (::access(env, X_OK) == 0) return env;
    throw IoError(env, "SINEW_MESH_IMPORT", "the mesh importer is not an executable file");
  }
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    tried.push_back(self.parent_path() / kHelperName);
    if (::access(tried.back().c_str(), X_OK) == 0) return tried.back();
  }
#ifdef SINEW_MESH_IMPORT_BUILD_PATH
  tried.emplace_back(SINEW_MESH_IMPORT_BUILD_PATH);
  if (::access(tried.back().c_str(), X_OK) == 0) return tried.back();
#endif
  std::string where;
  for (const auto& p : tried) where += (where.empty() ? "" : ", ") + p.string();
  throw IoError(kHelperName, "",
                "the mesh importer is missing (looked at " + where +
                    "); build it with the tools or name it with SINEW_MESH_IMPORT");
}

ImportedMesh import_mesh_isolated(const std::filesystem::path& file,
                                  const MeshImportOptions& options) {
  const std::string name = file.string();
  std::filesystem::path helper = options.helper;
  if (helper.empty()) {
    try {
      helper = find_mesh_import_helper();
    } catch (const IoError& e) {
      throw IoError(name, "", std::string("cannot read it: ") + e.what());
    }
  }
  const double timeout =
      options.timeout_seconds > 0 ? options.timeout_seconds : default_timeout(file);

  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw IoError(name, "",
                  std::string("cannot make a pipe for the mesh importer: ") + std::strerror(errno));
  Fd read_end{fds[0]}, write_end{fds[1]};

  // The child: stdout is the pipe, stdin and stderr /dev/null (assimp's assertion text is not the
  // tool's output; the error names the signal), default signal handling and an empty mask.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, write_end.fd, STDOUT_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  sigaddset(&defaults, SIGSEGV);
  sigaddset(&defaults, SIGBUS);
  sigaddset(&defaults, SIGABRT);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  std::string helper_arg = helper.string(), dashes = "--", file_arg = name;
  char* argv[] = {helper_arg.data(), dashes.data(), file_arg.data(), nullptr};
  Child child;
  const int spawned = ::posix_spawn(&child.pid, helper.c_str(), &actions, &attr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (spawned != 0) {
    child.pid = -1;
    throw IoError(
        name, "",
        "cannot start the mesh importer " + helper.string() + ": " + std::strerror(spawned));
  }
  ::close(write_end.fd);
  write_end.fd = -1;

  // Read until the child closes the pipe, or the deadline.
  const auto deadline = Clock::now() + std::chrono::duration<double>(timeout);
  auto ms_left = [&] {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
    return static_cast<int>(std::max<long long>(0, std::min<long long>(left.count(), 1 << 30)));
  };
  const std::string timed_out = "assimp did not finish reading it in " +
                                std::to_string(static_cast<long long>(std::ceil(timeout))) +
                                " s (stopped; SINEW_MESH_IMPORT_TIMEOUT gives it longer)";
  std::string bytes;
  std::vector<char> block(1 << 16);
  for (;;) {
    pollfd p{read_end.fd, POLLIN, 0};
    const int ready = ::poll(&p, 1, ms_left());
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0)
      throw IoError(name, "", std::string("reading the mesh importer: ") + std::strerror(errno));
    if (ready == 0) throw FormatError(name, "", timed_out);
    const ssize_t n = ::read(read_end.fd, block.data(), block.size());
    if (n < 0 && errno == EINTR) continue;
    if (n < 0)
      throw IoError(name, "", std::string("reading the mesh importer: ") + std::strerror(errno));
    if (n == 0) break;
    bytes.append(block.data(), static_cast<std::size_t>(n));
  }

  // The child has closed its output; it exits next (a hang in its exit still meets the deadline).
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(child.pid, &status, WNOHANG);
    if (r == child.pid) break;
    if (r < 0 && errno != EINTR)
      throw IoError(name, "",
                    std::string("waiting for the mesh importer: ") + std::strerror(errno));
    if (ms_left() == 0) throw FormatError(name, "", timed_out);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  child.pid = -1;  // reaped

  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    throw FormatError(name, "",
                      "assimp crashed reading it (" + signal_text(sig) +
                          (sig == SIGKILL ? "; out of memory?" : "") +
                          "): a damaged or unsupported mesh file");
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw FormatError(name, "",
                      "the mesh importer " + helper.string() + " failed (exit status " +
                          std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + ")");
  }
  ImportOutcome o = decode_outcome(bytes, name);
  switch (o.kind) {
    case ImportOutcome::Kind::mesh:
      return std::move(o.mesh);
    case ImportOutcome::Kind::geometry_error: {
      GeometryError e(name, o.field, o.problem);
      if (o.index >= 0) e.at(o.index);
      throw e;
    }
    case ImportOutcome::Kind::io_error:
      throw IoError(name, o.field, o.problem);
    case ImportOutcome::Kind::format_error:
      break;
  }
  throw FormatError(name, o.field, o.problem);
}

}  // namespace sinew::voxelizer
