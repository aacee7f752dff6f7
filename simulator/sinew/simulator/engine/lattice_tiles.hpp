#pragma once
// Lattice tiles for the CUDA backend's tiled assembly (docs/cuda-backend.md, "Tiled assembly";
// paper §6.4: the voxel lattice gives each element's nodes by position, not by a stored list).
//
// A tile is a block of kTileNodes × kTileNodes node columns (x, y) and up to `layers` node layers
// (z) of the model's lattice. One CUDA block owns its nodes: it walks the tile's layers upwards,
// computes the forces of every element touching them (the kSlots × kSlots element slots of a layer,
// elements on the tile's rim computed by both neighbouring tiles), keeps them in shared memory and
// sums each node's entries there: the element force buffer never goes through DRAM.
//
// Per tile (arrays of fixed stride, −1 where the lattice has no node / element):
//  - window_node: (layers + 2) × kWindow × kWindow node ids, window layer L = node layer k0 − 1 + L,
//    window point (wx, wy) = lattice (x0 − 1 + wx, y0 − 1 + wy);
//  - slot_element: (layers + 1) × kSlots × kSlots element ids, element layer L = base layer
//    k0 − 1 + L, slot (sx, sy) = base (x0 − 1 + sx, y0 − 1 + sy); it covers window points
//    (sx .. sx+1, sy .. sy+1) of window layers L and L + 1;
//  - tile_layers: node layers the tile really has (≤ layers).
// The tile's own nodes are window points 1 .. kTileNodes of window layers 1 .. tile_layers.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "sinew/common/host_device.hpp"

namespace sinew::simulator {

inline constexpr int kTileNodes = 15;               // node columns per tile side
inline constexpr int kTileSlots = kTileNodes + 1;   // element slots per side: 16
inline constexpr int kTileWindow = kTileNodes + 2;  // window points per side: 17

struct LatticeTiles {
  int layers = 0;  // node layers per tile (the z chunk)
  std::vector<std::int32_t> tile_layers;
  std::vector<std::int32_t> window_node;
  std::vector<std::int32_t> slot_element;
  std::size_t count() const { return tile_layers.size(); }
  std::size_t window_stride() const { return std::size_t(layers + 2) * kTileWindow * kTileWindow; }
  std::size_t slot_stride() const { return std::size_t(layers + 1) * kTileSlots * kTileSlots; }
};

// Tiles over the present nodes (lattice coordinates, any order; ids are positions in the vectors).
// The z chunk is the smallest that still gives at least `min_tiles` tiles (all layers in one tile
// when the x-y tiling alone gives that many): fewer, taller tiles compute fewer rim elements twice.
// When the tiles would hold more than `max_slots` element slots in all (every tile's slot_stride,
// counted before anything is built), returns no tiles (count() == 0).
LatticeTiles make_lattice_tiles(const std::vector<std::array<std::int32_t, 3>>& node_lattice,
                                const std::vector<std::array<std::int32_t, 3>>& element_lattice,
                                std::size_t min_tiles, std::size_t max_slots = SIZE_MAX);

// Elements computed by the tiles per model element (≥ 1: rim elements are computed by every tile
// they touch, and z chunks repeat one element layer).
double tile_redundancy(const LatticeTiles& tiles, std::size_t elements);
// The share of the tiles' element slots that hold an element (a tile block walks every slot of
// every layer: a thin shell curving through many layers leaves most of them empty).
double tile_fill(const LatticeTiles& tiles);

// Whether tiled assembly should pay off (ForceAssembly::automatic): the tiles compute at most
// kTiledMaxRedundancy times the model's elements, and at least kTiledMinFill of their slots hold
// one. Measured on one H200 (docs/performance.md): the face-scale slab (redundancy 1.13, fill 0.65,
// one z chunk) ran 1.4× faster tiled than gathered; the skin block (9 voxel layers cut into z
// chunks, redundancy > 1.6) and the sparse 15k body were faster gathered.
inline constexpr double kTiledMaxRedundancy = 1.25;
inline constexpr double kTiledMinFill = 0.5;
bool tiles_pay_off(const LatticeTiles& tiles, std::size_t elements);
// The most slots tiles of a model of `elements` elements can have and still pay off (for
// make_lattice_tiles' max_slots: slots ≥ computed / fill, computed ≤ redundancy × elements).
inline std::size_t max_paying_slots(std::size_t elements) {
  return std::size_t(kTiledMaxRedundancy / kTiledMinFill * double(elements));
}

// The entries a tile node sums, in the fixed gather order (ascending element id, as the CPU's
// incidence; physics::gather_node_force): the node at window point (wx, wy) of node layer k takes
// corner c of slot s, first from the elements below it (element layer k − 1, their top corners
// 4 + c), then from those above (layer k, bottom corners c). Entry q = 0..3 of each half:
//   slot  (wx−1, wy−1), (wx, wy−1), (wx−1, wy), (wx, wy)
//   corner      2          3           1          0       (hex8/VTK order, z = 0 face)
SINEW_HD_INLINE int tile_gather_slot(int wx, int wy, int q) {
  return (wy - 1 + (q >> 1)) * kTileSlots + (wx - 1 + (q & 1));
}
SINEW_HD_INLINE int tile_gather_corner(int q) {
  return q == 0 ? 2 : (q == 1 ? 3 : (q == 2 ? 1 : 0));
}

}  // namespace sinew::simulator
