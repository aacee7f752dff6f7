// Lattice tiles (the CUDA backend's tiled assembly): every node owned by exactly one tile, and the
// entries a tile node sums, in the kernel's order, are exactly the node's incidence of the gather
// (ascending element id, the CPU's order). Checked on the host, so CI covers it without a GPU.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "engine_test_support.hpp"
#include "sinew/simulator/engine/benchmark_models.hpp"
#include "sinew/simulator/engine/lattice_tiles.hpp"
#include "sinew/simulator/engine/prepared_model.hpp"

namespace sinew::simulator::testing {
namespace {

// For every node: the (element · 8 + corner) entries its tile sums, in the kernel's order,
// skipping absent elements; each node must appear in exactly one tile.
std::vector<std::vector<std::int32_t>> tile_gather_lists(const LatticeTiles& t, std::size_t nodes) {
  std::vector<std::vector<std::int32_t>> out(nodes);
  std::vector<int> owners(nodes, 0);
  constexpr int kW = kTileWindow * kTileWindow, kS = kTileSlots * kTileSlots;
  for (std::size_t b = 0; b < t.count(); ++b) {
    const std::int32_t* w = t.window_node.data() + b * t.window_stride();
    const std::int32_t* s = t.slot_element.data() + b * t.slot_stride();
    for (int l = 1; l <= t.tile_layers[b]; ++l)
      for (int wy = 1; wy <= kTileNodes; ++wy)
        for (int wx = 1; wx <= kTileNodes; ++wx) {
          const std::int32_t i = w[l * kW + wy * kTileWindow + wx];
          if (i < 0) continue;
          ++owners[std::size_t(i)];
          auto& list = out[std::size_t(i)];
          for (int half = 0; half < 2; ++half)  // elements below (their top corners), then above
            for (int q = 0; q < 4; ++q) {
              const std::int32_t e = s[(l - 1 + half) * kS + tile_gather_slot(wx, wy, q)];
              if (e >= 0) list.push_back(e * 8 + (half == 0 ? 4 : 0) + tile_gather_corner(q));
            }
        }
  }
  for (std::size_t i = 0; i < nodes; ++i) EXPECT_EQ(owners[i], 1) << "node " << i;
  return out;
}

void expect_tiles_reproduce_gather(const formats::Model& model, std::size_t min_tiles) {
  Setup setup;
  const Plan plan = make_plan(model, setup);
  const PreparedModel p = prepare_model(model, setup, plan);
  const LatticeTiles t = make_lattice_tiles(model.node_lattice, model.element_lattice, min_tiles);
  ASSERT_GT(t.count(), 0u);
  const auto lists = tile_gather_lists(t, p.nodes);
  std::size_t mismatches = 0;
  for (std::size_t i = 0; i < p.nodes; ++i) {
    const std::vector<std::int32_t> want(p.incidence.begin() + p.incidence_offset[i],
                                         p.incidence.begin() + p.incidence_offset[i + 1]);
    if (lists[i] != want && ++mismatches <= 5)
      ADD_FAILURE() << "node " << i << ": tile gather differs from the incidence";
  }
  EXPECT_EQ(mismatches, 0u);
  // Every present element is computed by some tile; the windows give its corners' node ids.
  std::vector<char> seen(p.elements, 0);
  for (auto e : t.slot_element)
    if (e >= 0) seen[std::size_t(e)] = 1;
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), std::ptrdiff_t(p.elements));
}

TEST(LatticeTiles, FullBoxTilesReproduceTheGatherOrder) {
  // 40 × 20 × 4: x and y not multiples of the tile, one z chunk or several.
  const auto model = make_forehead_model(40, 20, 4, 0.5e-3);
  expect_tiles_reproduce_gather(model, 1);
  expect_tiles_reproduce_gather(model, 40);  // z split into chunks
  const auto t = make_lattice_tiles(model.node_lattice, model.element_lattice, 1);
  EXPECT_EQ(t.layers, 5);
  EXPECT_EQ(t.count(), 6u);  // 41 × 21 node columns: 3 × 2 tiles of 15 × 15
  // 6 columns: 2 z chunks give 12 tiles, 3 chunks (of 2, 2 and 1 node layers) the 13 asked for.
  const auto chunked = make_lattice_tiles(model.node_lattice, model.element_lattice, 13);
  EXPECT_EQ(chunked.layers, 2);
  EXPECT_EQ(chunked.count(), 18u);
}

TEST(LatticeTiles, SparseLatticeTilesReproduceTheGatherOrder) {
  // The soft body: a sparse lattice of ellipsoids (empty slots, empty windows, empty tiles).
  const auto model = make_soft_body_model(0.5, 2e-3);
  expect_tiles_reproduce_gather(model, 1);
  expect_tiles_reproduce_gather(model, 200);
}

// The automatic assembly's rule on the two benchmark lattices it separates (docs/performance.md):
// the face-scale slab (4 voxels thick, one z chunk) computes 13% of its elements twice and goes
// tiled; the skin block (9 voxels thick, cut into z chunks for 3 tiles per SM of an H200) would
// compute over 60% twice and stays gathered.
TEST(LatticeTiles, AutomaticAssemblyFollowsTheRedundancy) {
  const std::size_t min_tiles = 3 * 132;
  const auto slab = make_forehead_model();
  const auto ts = make_lattice_tiles(slab.node_lattice, slab.element_lattice, min_tiles);
  EXPECT_EQ(ts.layers, 5);
  EXPECT_NEAR(tile_redundancy(ts, slab.element_count()), 1.132, 0.002);
  EXPECT_NEAR(tile_fill(ts), 0.647, 0.002);
  EXPECT_TRUE(tiles_pay_off(ts, slab.element_count()));
  const auto block = make_skin_block_model();
  const auto tb = make_lattice_tiles(block.node_lattice, block.element_lattice, min_tiles);
  EXPECT_LT(tb.layers, 10);
  EXPECT_GT(tile_redundancy(tb, block.element_count()), 1.6);
  EXPECT_FALSE(tiles_pay_off(tb, block.element_count()));
}

// A thin shell curving through many lattice layers (4 voxels thick, rising one layer every 4
// voxels in x, like a forehead voxelized in a box): few slots of a tile's layers hold an element,
// so tiles do not pay off, and with max_paying_slots they are not even built.
TEST(LatticeTiles, CurvedShellStaysGathered) {
  formats::Model shell;
  for (int k = 0; k < 93; ++k)  // sorted by (k, j, i)
    for (int j = 0; j < 90; ++j)
      for (int i = 0; i < 360; ++i)
        if (k >= i / 4 && k < i / 4 + 4) shell.element_lattice.push_back({i, j, k});
  formats::build_lattice_topology(shell);
  const std::size_t e = shell.element_count();
  const auto t = make_lattice_tiles(shell.node_lattice, shell.element_lattice, 132);
  EXPECT_EQ(t.layers, 94);  // 25 × 7 columns: one z chunk over all 94 node layers
  EXPECT_LT(tile_redundancy(t, e), kTiledMaxRedundancy);
  EXPECT_LT(tile_fill(t), 0.1);
  EXPECT_FALSE(tiles_pay_off(t, e));
  const auto none =
      make_lattice_tiles(shell.node_lattice, shell.element_lattice, 132, max_paying_slots(e));
  EXPECT_EQ(none.count(), 0u);
  EXPECT_FALSE(tiles_pay_off(none, e));
}

}  // namespace
}  // namespace sinew::simulator::testing
