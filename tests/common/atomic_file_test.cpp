// Files written in one go (common/atomic_file.hpp): a write that throws leaves neither the final
// name nor the temporary, and a tool ended by SIGINT, SIGTERM or SIGHUP while writing removes its
// temporaries ("*.tmp-<pid>" were left by `sinew-render --sequence` and `sinew-export` stopped by
// SIGTERM: issue 33). The signal cases run in a forked child, which the signal ends.
#include "sinew/common/atomic_file.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "sinew/common/tool.hpp"

namespace sinew {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() /
                   ("sinew_atomic_file_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.push_back(entry.path().filename());
  std::sort(names.begin(), names.end());
  return names;
}

void write(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Runs child() in a forked process and returns its wait status.
int in_child(const std::function<void()>& child) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    child();
    ::_exit(0);
  }
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, 0), pid);
  return status;
}

TEST(AtomicFile, AWriteThatThrowsLeavesNothing) {
  const auto dir = scratch("throw");
  EXPECT_THROW(write_atomically((dir / "a.txt").string(),
                                [](const std::string& tmp) {
                                  write(tmp, "half");
                                  throw std::runtime_error("disk full");
                                }),
               std::runtime_error);
  EXPECT_TRUE(names_in(dir).empty());
  write_text_atomically((dir / "b.txt").string(), "whole");
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"b.txt"});
}

// A tool (tool::run) stopped by each signal while two files are being written and one is done:
// the done one stays, the temporaries go, and the process ends by the signal.
TEST(AtomicFile, ASignalEndingAToolRemovesItsTemporaries) {
  for (const int sig : {SIGTERM, SIGINT, SIGHUP}) {
    const auto dir = scratch("signal_" + std::to_string(sig));
    const int status = in_child([&] {
      tool::run("sinew-test", [&] {
        write_text_atomically((dir / "frame_0000.png").string(), "done");
        TemporaryFile a((dir / "frame_0001.png").string());
        write(a.path(), "being written");
        TemporaryFile b((dir / "out.glb").string());
        write(b.path(), "being written");
        std::raise(sig);
        return tool::kExitOk;
      });
    });
    ASSERT_TRUE(WIFSIGNALED(status)) << "signal " << sig << ": status " << status;
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_EQ(names_in(dir), std::vector<std::string>{"frame_0000.png"}) << "signal " << sig;
    fs::remove_all(dir);
  }
}

// A signal the process was started with ignored (nohup, a background job) stays ignored.
TEST(AtomicFile, AnIgnoredSignalStaysIgnored) {
  const int status = in_child([] {
    std::signal(SIGTERM, SIG_IGN);
    remove_temporaries_on_signal();
    std::raise(SIGTERM);
    ::_exit(7);
  });
  ASSERT_TRUE(WIFEXITED(status)) << status;
  EXPECT_EQ(WEXITSTATUS(status), 7);
}

// A temporary committed or destroyed is no longer tracked: a later signal removes only the
// temporaries still being written, and the committed file stays.
TEST(AtomicFile, OnlyTheTemporariesStillBeingWrittenAreRemoved) {
  const auto dir = scratch("tracked");
  const int status = in_child([&] {
    remove_temporaries_on_signal();
    for (int i = 0; i < 2 * int(kMaxTrackedTemporaries); ++i) {
      TemporaryFile done((dir / ("f" + std::to_string(i))).string());
      write(done.path(), "x");
      if (i % 2 == 0) done.commit();
    }
    TemporaryFile open((dir / "open").string());
    write(open.path(), "y");
    std::raise(SIGTERM);
  });
  ASSERT_TRUE(WIFSIGNALED(status)) << status;
  const auto names = names_in(dir);
  EXPECT_EQ(names.size(), kMaxTrackedTemporaries);  // f0, f2, ...: the committed ones
  for (const auto& name : names) EXPECT_EQ(name.find(".tmp-"), std::string::npos) << name;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sinew
