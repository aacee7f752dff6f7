#include "sinew/postprocess/gltf_writer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <limits>
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

// Adds `count` × 3 floats as a VEC3 float accessor, with its min and max when `with_bounds` (glTF
// requires them on POSITION, morph targets included); returns the accessor's index.
int vec3_accessor(Builder& b, const std::vector<float>& p, std::size_t count,
                  bool with_bounds = true) {
  const int view = b.view(p.data(), p.size() * 4, kArrayBuffer);
  nlohmann::json acc = {{"bufferView", view},
                        {"byteOffset", 0},
                        {"componentType", kFloat},
                        {"count", count},
                        {"type", "VEC3"}};
  if (with_bounds) {
    const auto [lo, hi] = bounds(p.data(), count);
    acc["min"] = lo;
    acc["max"] = hi;
  }
  return b.accessor(std::move(acc));
}

}  // namespace

FrameTiming write_glb(const std::string& path, const SurfaceAnimation& a, const GltfOptions& o) {
  validate(a);
  const auto timing = frame_timing(a.times, {.fps = o.fps, .time_scale = o.time_scale});
  // Vertices split at texture seams (identity without UVs); per-vertex data is computed on the
  // surface and copied to its split vertices (`out`).
  const SeamSplit split = split_at_seams(a);
  const std::size_t nv = split.vertex.size(), nf = a.frame_count();
  auto out = [&](const std::vector<float>& v, std::size_t width) {
    return gather_rows(v, width, split.vertex);
  };
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
  // Normals of the turned poses: turning is a rotation, so normals of turned positions are the
  // turned normals. Up (+Y) is the fallback for a vertex of no proper triangle.
  const auto rest_normals = smooth_normals(rest, a.triangles, {0.0f, 1.0f, 0.0f});

  Builder b;
  std::vector<std::uint32_t> indices(split.triangles.begin(), split.triangles.end());
  const int idx_view = b.view(indices.data(), indices.size() * 4, kElementArrayBuffer);
  const int idx_acc = b.accessor({{"bufferView", idx_view},
                                  {"byteOffset", 0},
                                  {"componentType", kUnsignedInt},
                                  {"count", indices.size()},
                                  {"type", "SCALAR"}});
  nlohmann::json attributes = {{"POSITION", vec3_accessor(b, out(rest, 3), nv)},
                               {"NORMAL", vec3_accessor(b, out(rest_normals, 3), nv, false)}};
  if (a.has_uvs()) {
    // glTF's texture origin is the image's top-left corner, OBJ's (stored) the bottom-left.
    std::vector<float> uv(2 * nv);
    for (std::size_t i = 0; i < nv; ++i) {
      const auto q = static_cast<std::size_t>(split.uv[i]);
      uv[2 * i] = a.uvs[2 * q];
      uv[2 * i + 1] = 1.0f - a.uvs[2 * q + 1];
    }
    const int view = b.view(uv.data(), uv.size() * 4, kArrayBuffer);
    attributes["TEXCOORD_0"] = b.accessor({{"bufferView", view},
                                           {"byteOffset", 0},
                                           {"componentType", kFloat},
                                           {"count", nv},
                                           {"type", "VEC2"}});
  }
  nlohmann::json material = {{"name", "skin"},
                             {"pbrMetallicRoughness",
                              {{"baseColorFactor", {0.84, 0.69, 0.59, 1.0}},
                               {"metallicFactor", 0.0},
                               {"roughnessFactor", 0.6}}}};
  if (o.color != VertexScalar::none) {
    if (o.color == VertexScalar::von_mises && o.color_values.size() != nf) {
      throw ConfigError(path, "--color", "von Mises colours need the stress of every frame");
    }
    const auto peak =
        o.color_values.empty() ? peak_displacement(a) : peak_over_frames(o.color_values);
    const float max = *std::max_element(peak.begin(), peak.end());
    attributes["COLOR_0"] = vec3_accessor(b, out(viridis_colors(peak, max), 3), nv, false);
    const auto peak_out = out(peak, 1);
    const int view = b.view(peak_out.data(), peak_out.size() * 4, kArrayBuffer);
    attributes[gltf_attribute_name(o.color)] = b.accessor({{"bufferView", view},
                                                           {"byteOffset", 0},
                                                           {"componentType", kFloat},
                                                           {"count", nv},
                                                           {"type", "SCALAR"}});
    material["pbrMetallicRoughness"]["baseColorFactor"] = {1.0, 1.0, 1.0, 1.0};
    const bool stress = o.color == VertexScalar::von_mises;
    material["extras"] = {
        {"color", stress ? "peak von Mises stress, viridis" : "peak displacement, viridis"},
        {"unit", unit_of(o.color)},
        {stress ? "min_pa" : "min_m", 0.0},
        {stress ? "max_pa" : "max_m", max}};
  }
  nlohmann::json targets = nlohmann::json::array(), names = nlohmann::json::array();
  for (std::size_t k = 0; k < nf; ++k) {
    auto delta = turn(a.frames[k]);
    auto normal = smooth_normals(delta, a.triangles, {0.0f, 1.0f, 0.0f});
    for (std::size_t i = 0; i < delta.size(); ++i) {
      delta[i] -= rest[i];
      normal[i] -= rest_normals[i];
    }
    targets.push_back({{"POSITION", vec3_accessor(b, out(delta, 3), nv)},
                       {"NORMAL", vec3_accessor(b, out(normal, 3), nv, false)}});
    names.push_back(fmt::format("frame_{:04}", k));
  }
  std::vector<float> weights(nf * nf, 0.0f);
  for (std::size_t k = 0; k < nf; ++k) weights[k * nf + k] = 1.0f;
  const auto& times = timing.time;
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

  nlohmann::json primitive = {{"attributes", attributes},
                              {"indices", idx_acc},
                              {"material", 0},
                              {"mode", 4},
                              {"targets", targets}};
  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "sinew-export"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}, {"name", a.name}}}},
      {"materials", {material}},
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
         {"channels", {{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}}},
         {"extras", {{"fps", timing.fps}, {"frames", timing.frame}}}}}},
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
  std::string bytes;
  bytes.reserve(total);
  auto put = [&](const void* p, std::size_t n) { bytes.append(static_cast<const char*>(p), n); };
  const std::uint32_t header[3] = {kMagic, 2, static_cast<std::uint32_t>(total)};
  const std::uint32_t json_head[2] = {static_cast<std::uint32_t>(json.size()), kJsonChunk};
  const std::uint32_t bin_head[2] = {static_cast<std::uint32_t>(b.bin.size()), kBinChunk};
  put(header, sizeof header);
  put(json_head, sizeof json_head);
  put(json.data(), json.size());
  put(bin_head, sizeof bin_head);
  put(b.bin.data(), b.bin.size());
  write_text_atomically(path, bytes);
  return timing;
}

}  // namespace sinew::postprocess
