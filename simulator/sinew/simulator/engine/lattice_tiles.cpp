#include "sinew/simulator/engine/lattice_tiles.hpp"

#include <algorithm>
#include <limits>

namespace sinew::simulator {
namespace {

using Lattice = std::array<std::int32_t, 3>;

// Dense lookup lattice point -> id over a bounding box (−1 outside or absent).
class DenseIndex {
 public:
  DenseIndex(const std::vector<Lattice>& points, const Lattice& lo, const Lattice& hi) : lo_(lo) {
    for (int k = 0; k < 3; ++k) dims_[std::size_t(k)] = hi[std::size_t(k)] - lo[std::size_t(k)] + 1;
    ids_.assign(std::size_t(dims_[0]) * std::size_t(dims_[1]) * std::size_t(dims_[2]), -1);
    for (std::size_t n = 0; n < points.size(); ++n) ids_[offset(points[n])] = std::int32_t(n);
  }
  std::int32_t at(std::int32_t i, std::int32_t j, std::int32_t k) const {
    const Lattice p{i, j, k};
    for (std::size_t d = 0; d < 3; ++d)
      if (p[d] < lo_[d] || p[d] >= lo_[d] + dims_[d]) return -1;
    return ids_[offset(p)];
  }

 private:
  std::size_t offset(const Lattice& p) const {
    return (std::size_t(p[2] - lo_[2]) * std::size_t(dims_[1]) + std::size_t(p[1] - lo_[1])) *
               std::size_t(dims_[0]) +
           std::size_t(p[0] - lo_[0]);
  }
  Lattice lo_, dims_{};
  std::vector<std::int32_t> ids_;
};

}  // namespace

LatticeTiles make_lattice_tiles(const std::vector<Lattice>& node_lattice,
                                const std::vector<Lattice>& element_lattice, std::size_t min_tiles,
                                std::size_t max_slots) {
  LatticeTiles t;
  if (node_lattice.empty()) return t;
  Lattice lo{std::numeric_limits<std::int32_t>::max(), std::numeric_limits<std::int32_t>::max(),
             std::numeric_limits<std::int32_t>::max()};
  Lattice hi{std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::min(),
             std::numeric_limits<std::int32_t>::min()};
  for (const auto& p : node_lattice)
    for (std::size_t d = 0; d < 3; ++d) {
      lo[d] = std::min(lo[d], p[d]);
      hi[d] = std::max(hi[d], p[d]);
    }
  const int tx = (hi[0] - lo[0]) / kTileNodes + 1, ty = (hi[1] - lo[1]) / kTileNodes + 1;
  const int nz = hi[2] - lo[2] + 1;
  // Columns that hold any node (an empty column gives no tile in any chunk).
  std::vector<char> column(std::size_t(tx) * std::size_t(ty), 0);
  for (const auto& p : node_lattice)
    column[std::size_t((p[1] - lo[1]) / kTileNodes) * std::size_t(tx) +
           std::size_t((p[0] - lo[0]) / kTileNodes)] = 1;
  const auto columns = std::size_t(std::count(column.begin(), column.end(), 1));
  int chunks = 1;
  while (chunks < nz && columns * std::size_t(chunks) < min_tiles) ++chunks;
  t.layers = (nz + chunks - 1) / chunks;
  if (double(columns) * double(chunks) * double(t.slot_stride()) > double(max_slots)) return t;
  const DenseIndex nodes(node_lattice, lo, hi);
  const DenseIndex elements(element_lattice, lo, hi);  // element bases lie inside the node box

  const std::size_t ws = t.window_stride(), ss = t.slot_stride();
  for (int cz = 0; cz * t.layers < nz; ++cz)
    for (int cy = 0; cy < ty; ++cy)
      for (int cx = 0; cx < tx; ++cx) {
        if (!column[std::size_t(cy) * std::size_t(tx) + std::size_t(cx)]) continue;
        const int x0 = lo[0] + cx * kTileNodes, y0 = lo[1] + cy * kTileNodes;
        const int k0 = lo[2] + cz * t.layers;
        const int layers = std::min(t.layers, hi[2] + 1 - k0);
        const std::size_t w0 = t.window_node.size(), s0 = t.slot_element.size();
        t.window_node.resize(w0 + ws, -1);
        t.slot_element.resize(s0 + ss, -1);
        bool any = false;
        for (int l = 0; l < layers + 2; ++l)
          for (int wy = 0; wy < kTileWindow; ++wy)
            for (int wx = 0; wx < kTileWindow; ++wx) {
              const auto id = nodes.at(x0 - 1 + wx, y0 - 1 + wy, k0 - 1 + l);
              t.window_node[w0 + (std::size_t(l) * kTileWindow + std::size_t(wy)) * kTileWindow +
                            std::size_t(wx)] = id;
              any = any || (id >= 0 && l >= 1 && l <= layers && wx >= 1 && wx <= kTileNodes &&
                            wy >= 1 && wy <= kTileNodes);
            }
        if (!any) {  // a chunk of a column with no node of its own
          t.window_node.resize(w0);
          t.slot_element.resize(s0);
          continue;
        }
        for (int l = 0; l < layers + 1; ++l)
          for (int sy = 0; sy < kTileSlots; ++sy)
            for (int sx = 0; sx < kTileSlots; ++sx)
              t.slot_element[s0 + (std::size_t(l) * kTileSlots + std::size_t(sy)) * kTileSlots +
                             std::size_t(sx)] = elements.at(x0 - 1 + sx, y0 - 1 + sy, k0 - 1 + l);
        t.tile_layers.push_back(layers);
      }
  return t;
}

namespace {
std::size_t computed_slots(const LatticeTiles& tiles) {
  return std::size_t(std::count_if(tiles.slot_element.begin(), tiles.slot_element.end(),
                                   [](std::int32_t e) { return e >= 0; }));
}
}  // namespace

double tile_redundancy(const LatticeTiles& tiles, std::size_t elements) {
  return elements ? double(computed_slots(tiles)) / double(elements) : 1.0;
}

double tile_fill(const LatticeTiles& tiles) {
  return tiles.slot_element.empty()
             ? 0.0
             : double(computed_slots(tiles)) / double(tiles.slot_element.size());
}

bool tiles_pay_off(const LatticeTiles& tiles, std::size_t elements) {
  return tiles.count() > 0 && tile_redundancy(tiles, elements) <= kTiledMaxRedundancy &&
         tile_fill(tiles) >= kTiledMinFill;
}

}  // namespace sinew::simulator
