// The input-file check every reader makes first (common/input_file.hpp): a folder, a FIFO, a
// device or a missing file is an IoError naming the path and what it is, never a read that blocks
// (a FIFO with no writer) or never ends (/dev/zero). Found by scripts/fuzz_inputs.py: every tool
// hung on a FIFO in place of its input and the YAML readers on a link to /dev/zero.
#include "sinew/common/input_file.hpp"

#include <sys/stat.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("sinew_input_file_test_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A folder holding a FIFO with no writer (pipe.yaml) and a link to /dev/zero (zero.yaml).
fs::path scratch_with_pipe_and_device(const std::string& name) {
  const auto dir = scratch(name);
  EXPECT_EQ(::mkfifo((dir / "pipe.yaml").c_str(), 0600), 0);
  fs::create_symlink("/dev/zero", dir / "zero.yaml");
  return dir;
}

std::string io_error(const std::function<void()>& read) {
  try {
    read();
  } catch (const IoError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an IoError";
  return "";
}

TEST(InputFile, AcceptsARegularFileAndALinkToOne) {
  const auto dir = scratch("regular");
  std::ofstream(dir / "a.yaml") << "a: 1\n";
  fs::create_symlink(dir / "a.yaml", dir / "link.yaml");
  EXPECT_NO_THROW(require_regular_file(dir / "a.yaml", "scene file"));
  EXPECT_NO_THROW(require_regular_file(dir / "link.yaml", "scene file"));
  fs::remove_all(dir);
}

TEST(InputFile, RejectsAFolderAFifoADeviceAndAMissingFile) {
  const auto dir = scratch_with_pipe_and_device("kinds");
  const auto fifo = dir / "pipe.yaml";
  EXPECT_EQ(io_error([&] { require_regular_file(fifo, "scene file"); }),
            fifo.string() + ": the scene file is a FIFO (named pipe), not a regular file");
  EXPECT_EQ(io_error([&] { require_regular_file(dir, "model file"); }),
            dir.string() + ": the model file is a folder, not a regular file");
  EXPECT_EQ(
      io_error([&] { require_regular_file(dir / "zero.yaml", "spec file"); }),
      (dir / "zero.yaml").string() + ": the spec file is a character device, not a regular file");
  EXPECT_EQ(
      io_error([&] { require_regular_file(dir / "none.yaml", "spec file"); }),
      (dir / "none.yaml").string() + ": cannot open the spec file: No such file or directory");
  fs::remove_all(dir);
}

// Without the check, reading the FIFO blocked for good (the test then ran into ctest's timeout)
// and reading /dev/zero grew the string until memory ran out.
TEST(InputFile, TextReaderNeitherBlocksOnAFifoNorReadsADeviceForEver) {
  const auto dir = scratch_with_pipe_and_device("reader");
  const auto fifo = dir / "pipe.yaml";
  EXPECT_NE(io_error([&] { read_text_file(fifo, "scene file"); }).find("FIFO"), std::string::npos);
  EXPECT_NE(io_error([&] { read_text_file(dir / "zero.yaml", "scene file"); }).find("device"),
            std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace sinew
