#include "sinew/postprocess/gltf_writer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <vector>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"

namespace sinew::postprocess {
namespace {

constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kBinChunk = 0x004E4942;   // "BIN\0"
constexpr int kFloat = 5126, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

struct Builder {
  std::vector<std::uint8_t> bin;
  nlohmann::json views = nlohmann::json::array();
  nlohmann::json accessors = nlohmann::json::array();

  // Appends `bytes` as a new bufferView starting at a multiple of 4; returns its index.
  int view(const void* data, std::size_t bytes, int target) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    nlohmann::json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target != 0) v["target"] = target;
    const auto* p = static_cast<const std::uint8_t*>(data);
    bin.insert(bin.end(), p, p + bytes);
    views.push_back(v);
    return static_cast<int>(views.size()) - 1;
  }
  int accessor(nlohmann::json a) {
    accessors.push_back(std::move(a));
    return static_cast<int>(accessors.size()) - 1;
  }
};

// min and max per component of V × 3 floats.
std::pair<nlohmann::json, nlohmann::json> bounds(const float* p, std::size_t count) {
  float lo[3], hi[3];
  for (int k = 0; k < 3; ++k) {
    lo[k] = std::numeric_limits<float>::max();
    hi[k] = std::numeric_limits<float>::lowest();
  }
  for (std::size_t i = 0; i < count; ++i) {
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], p[3 * i + k]);
      hi[k] = std::max(hi[k], p[3 * i + k]);
    }
  }
  return {nlohmann::json{lo[0], lo[1], lo[2]}, nlohmann::json{hi[0], hi[1], hi[2]}};
}

// Adds `count` × 3 floats as a VEC3 float accessor with its min and max (glTF requires them on
// POSITION, morph targets included); returns the accessor's index.
int vec3_accessor(Builder& b, const std::vector<float>& p, std::size_t count) {
  const auto [lo, hi] = bounds(p.data(), count);
  const int view = b.view(p.data(), p.size() * 4, kArrayBuffer);
  return b.accessor({{"bufferView", view},
                     {"byteOffset", 0},
                     {"componentType", kFloat},
                     {"count", count},
                     {"type", "VEC3"},
                     {"min", lo},
                     {"max", hi}});
}

}  // namespace

void write_glb(const std::string& path, const SurfaceAnimation& a, const GltfOptions& o) {
  if (!(o.time_scale > 0)) throw ConfigError("", "time_scale", "must be positive");
  validate(a);
  const std::size_t nv = a.vertex_count(), nf = a.frame_count();
  auto turn = [&](std::vector<float> p) {
    if (o.up == UpAxis::z) {
      for (std::size_t i = 0; i + 2 < p.size(); i += 3) {
        const float y = p[i + 1];
        p[i + 1] = p[i + 2];
        p[i + 2] = -y;
      }
    }
    return p;
  };
  const auto rest = turn(a.rest);

  Builder b;
  std::vector<std::uint32_t> indices(a.triangles.begin(), a.triangles.end());
  const int idx_view = b.view(indices.data(), indices.size() * 4, kElementArrayBuffer);
  const int idx_acc = b.accessor({{"bufferView", idx_view},
                                  {"byteOffset", 0},
                                  {"componentType", kUnsignedInt},
                                  {"count", indices.size()},
                                  {"type", "SCALAR"}});
  const int pos_acc = vec3_accessor(b, rest, nv);
  nlohmann::json targets = nlohmann::json::array(), names = nlohmann::json::array();
  for (std::size_t k = 0; k < nf; ++k) {
    auto delta = turn(a.frames[k]);
    for (std::size_t i = 0; i < delta.size(); ++i) delta[i] -= rest[i];
    targets.push_back({{"POSITION", vec3_accessor(b, delta, nv)}});
    names.push_back(fmt::format("frame_{:04}", k));
  }
  std::vector<float> times(nf), weights(nf * nf, 0.0f);
  for (std::size_t k = 0; k < nf; ++k) {
    times[k] = static_cast<float>((a.times[k] - a.times[0]) * o.time_scale);
    weights[k * nf + k] = 1.0f;
  }
  // Float rounding must not make two key times equal (the input must increase strictly).
  for (std::size_t k = 1; k < nf; ++k) {
    if (!(times[k] > times[k - 1])) {
      times[k] = std::nextafter(times[k - 1], std::numeric_limits<float>::max());
    }
  }
  const int time_view = b.view(times.data(), times.size() * 4, 0);
  const int time_acc = b.accessor({{"bufferView", time_view},
                                   {"byteOffset", 0},
                                   {"componentType", kFloat},
                                   {"count", nf},
                                   {"type", "SCALAR"},
                                   {"min", {times.front()}},
                                   {"max", {times.back()}}});
  const int w_view = b.view(weights.data(), weights.size() * 4, 0);
  const int w_acc = b.accessor({{"bufferView", w_view},
                                {"byteOffset", 0},
                                {"componentType", kFloat},
                                {"count", weights.size()},
                                {"type", "SCALAR"}});
  while (b.bin.size() % 4 != 0) b.bin.push_back(0);

  nlohmann::json primitive = {{"attributes", {{"POSITION", pos_acc}}},
                              {"indices", idx_acc},
                              {"mode", 4},
                              {"targets", targets}};
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "sinew-export"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}, {"name", a.name}}}},
      {"meshes",
       {{{"name", a.name},
         {"primitives", {primitive}},
         {"weights", std::vector<float>(nf, 0.0f)},
         {"extras", {{"targetNames", names}}}}}},
      {"animations",
       {{{"name", "simulation"},
         {"samplers",
          {{{"input", time_acc},
            {"output", w_acc},
            {"interpolation", o.linear ? "LINEAR" : "STEP"}}}},
         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}}}}}},
      {"accessors", b.accessors},
      {"bufferViews", b.views},
      {"buffers", {{{"byteLength", b.bin.size()}}}},
  };
  std::string json = doc.dump();
  while (json.size() % 4 != 0) json.push_back(' ');

  const std::uint64_t total = 12 + 8 + json.size() + 8 + b.bin.size();
  if (total > std::numeric_limits<std::uint32_t>::max()) {
    throw IoError(path, "",
                  fmt::format("the animation needs {} bytes, over glTF's 4 GiB limit", total));
  }
  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  TemporaryFile out(path);
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(out.path().c_str(), "wb"));
  if (!f) throw IoError(path, "", "cannot open for writing: " + write_failure(errno));
  const std::uint32_t header[3] = {kMagic, 2, static_cast<std::uint32_t>(total)};
  const std::uint32_t json_head[2] = {static_cast<std::uint32_t>(json.size()), kJsonChunk};
  const std::uint32_t bin_head[2] = {static_cast<std::uint32_t>(b.bin.size()), kBinChunk};
  bool ok = std::fwrite(header, 4, 3, f.get()) == 3 && std::fwrite(json_head, 4, 2, f.get()) == 2 &&
            std::fwrite(json.data(), 1, json.size(), f.get()) == json.size() &&
            std::fwrite(bin_head, 4, 2, f.get()) == 2 &&
            std::fwrite(b.bin.data(), 1, b.bin.size(), f.get()) == b.bin.size();
  ok = ok && std::fflush(f.get()) == 0 && std::fclose(f.release()) == 0;
  if (!ok) throw IoError(path, "", "cannot write: " + write_failure(errno));
  out.commit();
}

}  // namespace sinew::postprocess
