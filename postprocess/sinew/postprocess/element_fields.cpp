#include "sinew/postprocess/element_fields.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "sinew/common/error.hpp"
#include "sinew/postprocess/results_file.hpp"

namespace sinew::postprocess {

namespace h5 = formats::hdf5;

namespace {

// The output field that writes each element dataset (docs/scene-format.md, output.fields).
std::string field_of(const std::string& dataset) {
  if (dataset == "/frames/von_mises") return "stress";
  if (dataset == "/frames/J") return "J";
  return dataset.substr(dataset.rfind('/') + 1);
}

// Natural-coordinate signs of the 8 hex8 corners (VTK order, docs/model-format.md).
constexpr std::array<std::array<int, 3>, 8> kSigns = {{{-1, -1, -1},
                                                       {1, -1, -1},
                                                       {1, 1, -1},
                                                       {-1, 1, -1},
                                                       {-1, -1, 1},
                                                       {1, -1, 1},
                                                       {1, 1, 1},
                                                       {-1, 1, 1}}};

}  // namespace

std::vector<std::vector<float>> element_field_at_vertices(const std::string& path,
                                                          const SurfaceAnimation& a,
                                                          const std::string& dataset) {
  auto file = open_results(path);
  if (!h5::exists(file, dataset)) {
    throw FormatError(path, dataset,
                      fmt::format("missing dataset: run the scene with output.fields including "
                                  "{}",
                                  field_of(dataset)));
  }
  for (const auto* ds : {"/mesh/connectivity", "/mesh/rest_positions"}) {
    if (!h5::exists(file, ds)) throw FormatError(path, ds, "missing dataset");
  }
  const auto conn_shape = h5::shape(file, "/mesh/connectivity", path);
  const auto rest_shape = h5::shape(file, "/mesh/rest_positions", path);
  if (conn_shape.size() != 2 || conn_shape[1] != 8) {
    throw FormatError(path, "/mesh/connectivity", "expected shape E × 8");
  }
  if (rest_shape.size() != 2 || rest_shape[1] != 3) {
    throw FormatError(path, "/mesh/rest_positions", "expected shape N × 3");
  }
  const auto e_count = static_cast<std::size_t>(conn_shape[0]);
  const auto n_count = static_cast<std::size_t>(rest_shape[0]);
  const auto shape = h5::shape(file, dataset, path);
  if (shape.size() != 2 || shape[1] != e_count || shape[0] < a.frame_count()) {
    throw FormatError(path, dataset,
                      fmt::format("expected shape F × {} with F ≥ {}", e_count, a.frame_count()));
  }
  const auto conn = h5::read<std::int32_t>(file, "/mesh/connectivity", path);
  for (std::size_t i = 0; i < conn.size(); ++i) {
    if (conn[i] < 0 || static_cast<std::size_t>(conn[i]) >= n_count) {
      throw FormatError(path, "/mesh/connectivity",
                        fmt::format("node id {} out of range [0, {})", conn[i], n_count))
          .at(static_cast<std::int64_t>(i / 8));
    }
  }
  std::vector<int> uses(n_count, 0);
  for (const auto n : conn) ++uses[static_cast<std::size_t>(n)];

  // Each vertex as a weighted sum of mesh nodes: 8 (node, weight) pairs.
  const std::size_t nv = a.vertex_count();
  std::vector<std::int32_t> node(8 * nv, 0);
  std::vector<double> weight(8 * nv, 0.0);
  if (!a.volume_nodes.empty()) {
    for (std::size_t v = 0; v < nv; ++v) {
      node[8 * v] = a.volume_nodes[v];
      weight[8 * v] = 1.0;
    }
  } else {
    const std::string group = "/surfaces/" + a.name;
    for (const auto& ds : {group + "/embedding_element", group + "/embedding_local"}) {
      if (!h5::exists(file, ds)) {
        throw FormatError(path, ds,
                          "missing dataset (results written before surfaces carried their "
                          "embedding): run the scene again to colour the surface by an element "
                          "field");
      }
    }
    const auto element = h5::read<std::int32_t>(file, group + "/embedding_element", path,
                                                static_cast<std::int64_t>(nv));
    const auto local =
        h5::read<double>(file, group + "/embedding_local", path, static_cast<std::int64_t>(3 * nv));
    for (std::size_t v = 0; v < nv; ++v) {
      if (element[v] < 0 || static_cast<std::size_t>(element[v]) >= e_count) {
        throw FormatError(path, group + "/embedding_element",
                          fmt::format("element id {} out of range [0, {})", element[v], e_count))
            .at(static_cast<std::int64_t>(v));
      }
      const double* xi = &local[3 * v];
      if (!std::isfinite(xi[0]) || !std::isfinite(xi[1]) || !std::isfinite(xi[2])) {
        throw FormatError(path, group + "/embedding_local", "non-finite natural coordinate")
            .at(static_cast<std::int64_t>(v));
      }
      const auto e = static_cast<std::size_t>(element[v]);
      for (std::size_t c = 0; c < 8; ++c) {
        node[8 * v + c] = conn[8 * e + c];
        weight[8 * v + c] = (1 + kSigns[c][0] * xi[0]) * (1 + kSigns[c][1] * xi[1]) *
                            (1 + kSigns[c][2] * xi[2]) / 8.0;
      }
    }
  }

  const auto values = h5::read<double>(file, dataset, path);
  std::vector<std::vector<float>> out(a.frame_count(), std::vector<float>(nv));
  std::vector<double> nodal(n_count);
  for (std::size_t f = 0; f < a.frame_count(); ++f) {
    std::fill(nodal.begin(), nodal.end(), 0.0);
    for (std::size_t e = 0; e < e_count; ++e) {
      const double s = values[f * e_count + e];
      if (!std::isfinite(s)) {
        throw FormatError(path, dataset,
                          fmt::format("non-finite value at element {} in frame {}", e, f))
            .at(static_cast<std::int64_t>(f));
      }
      for (std::size_t c = 0; c < 8; ++c) nodal[static_cast<std::size_t>(conn[8 * e + c])] += s;
    }
    for (std::size_t n = 0; n < n_count; ++n)
      if (uses[n] > 0) nodal[n] /= uses[n];
    for (std::size_t v = 0; v < nv; ++v) {
      double s = 0;
      for (std::size_t c = 0; c < 8; ++c)
        s += weight[8 * v + c] * nodal[static_cast<std::size_t>(node[8 * v + c])];
      out[f][v] = static_cast<float>(s);
    }
  }
  return out;
}

}  // namespace sinew::postprocess
