#include "sinew/postprocess/pc2_writer.hpp"

#include <fmt/format.h>

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::postprocess {
namespace {

static_assert(std::endian::native == std::endian::little,
              "PC2 and glTF are little endian; this writer stores native floats");

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

// Opens `tmp`, the temporary of the file `path` (errors name path).
File open_write(const std::string& tmp, const std::string& path) {
  File f(std::fopen(tmp.c_str(), "wb"));
  if (!f) throw IoError(path, "", "cannot open for writing: " + write_failure(errno));
  return f;
}

void put(std::FILE* f, const void* data, std::size_t bytes, const std::string& path) {
  if (bytes > 0 && std::fwrite(data, 1, bytes, f) != bytes) {
    throw IoError(path, "", "cannot write: " + write_failure(errno));
  }
}

void finish(File& f, const std::string& path) {
  if (std::fflush(f.get()) != 0 || std::ferror(f.get()) || std::fclose(f.release()) != 0) {
    throw IoError(path, "", "cannot write: " + write_failure(errno));
  }
}

}  // namespace

void write_pc2(const std::string& path, const SurfaceAnimation& a, const Pc2Options& o) {
  TemporaryFile out(path);
  auto f = open_write(out.path(), path);
  char header[kPc2HeaderBytes] = {};
  std::memcpy(header, "POINTCACHE2", 12);  // with its terminating NUL
  const std::int32_t version = 1, points = static_cast<std::int32_t>(a.vertex_count()),
                     samples = static_cast<std::int32_t>(a.frame_count());
  std::memcpy(header + 12, &version, 4);
  std::memcpy(header + 16, &points, 4);
  std::memcpy(header + 20, &o.start_frame, 4);
  std::memcpy(header + 24, &o.sample_rate, 4);
  std::memcpy(header + 28, &samples, 4);
  put(f.get(), header, sizeof header, path);
  for (const auto& frame : a.frames) put(f.get(), frame.data(), frame.size() * sizeof(float), path);
  finish(f, path);
  out.commit();
}

void write_obj(const std::string& path, const std::vector<float>& positions,
               const std::vector<std::int32_t>& triangles, const std::string& comment) {
  TemporaryFile out(path);
  auto f = open_write(out.path(), path);
  std::string text;
  text.reserve(positions.size() * 14 + triangles.size() * 8 + 64);
  if (!comment.empty()) text += "# " + comment + "\n";
  for (std::size_t i = 0; i + 2 < positions.size(); i += 3) {
    text +=
        fmt::format("v {:.9g} {:.9g} {:.9g}\n", positions[i], positions[i + 1], positions[i + 2]);
  }
  for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
    text +=
        fmt::format("f {} {} {}\n", triangles[t] + 1, triangles[t + 1] + 1, triangles[t + 2] + 1);
  }
  put(f.get(), text.data(), text.size(), path);
  finish(f, path);
  out.commit();
}

std::vector<std::string> write_obj_sequence(const std::string& directory, const SurfaceAnimation& a,
                                            const std::string& prefix) {
  std::error_code ec;
  std::filesystem::create_directories(directory, ec);
  if (ec) throw IoError(directory, "", "cannot create the directory: " + ec.message());
  const int digits =
      a.frame_count() > 10000 ? static_cast<int>(std::to_string(a.frame_count() - 1).size()) : 4;
  std::vector<std::string> paths;
  for (std::size_t k = 0; k < a.frame_count(); ++k) {
    const auto path =
        (std::filesystem::path(directory) / fmt::format("{}_{:0{}}.obj", prefix, k, digits))
            .string();
    write_obj(path, a.frames[k], a.triangles,
              fmt::format("sinew surface {} frame {} t = {:.9g} s", a.name, k, a.times[k]));
    paths.push_back(path);
  }
  return paths;
}

}  // namespace sinew::postprocess
