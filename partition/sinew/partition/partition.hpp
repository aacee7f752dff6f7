#pragma once
// Domain decomposition of a model's voxel lattice into slabs, one per rank or GPU
// (docs/multi-gpu.md). Owner computes with redundant halo elements:
//  - the node layers along one lattice axis (the longest, unless asked) are cut into P contiguous
//    ranges; part p owns the nodes of its layers,
//  - part p computes every element touching a node it owns (its own elements plus one layer of halo
//    elements on each inner side) and gathers its owned nodes' forces from them in the one-device
//    incidence order, so each owned node gets the bits one device gives it,
//  - its halo nodes (nodes of its elements it does not own) are received from their owners each
//    step: u(n+1) of 3 scalars per halo node, the only data exchanged per step.
// Each element also has one primary part (the owner of its base corner, hex8 node 0) that reports
// its J check and its energies, so every element is counted once.
//
// Cuts balance the work of each part (its owned nodes and computed elements, halos included), by
// the per-item costs of CostModel (relative to a single-material element without muscle).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sinew/formats/model.hpp"
#include "sinew/simulator/engine/plan.hpp"

namespace sinew::partition {

using formats::Index;

// Relative per-step cost of each kind of item, in units of a single-material element without muscle
// (docs/multi-gpu.md "Balance"; measured on an H100 with ncu, docs/performance.md "Per kernel" and
// "Stage shares", forehead 0.5 mm): a muscle element 1.3 (9.1 µs for its 324 blocks against 10.9
// µs for 494: 28 vs 22 ns per block), a multi-material element 1.0 (its own parameter row is one
// more read in a latency-bound kernel: no measurable difference per block), a node 0.8 (gather and
// update: 0.0375 ms for 636k nodes against 0.0384 ms for 506k elements), a sliding node 2.5 more
// (sliding 28.7% of the 0.0835 ms step for 127k sliding nodes).
struct CostModel {
  double element = 1.0;
  double multi_material = 1.0;
  double muscle = 1.3;
  double node = 0.8;
  double sliding_node = 2.5;  // added to `node`
};

// Per-item work of a run: E element costs and N node costs (CostModel over the plan's collections
// and the simulated sliding bindings).
struct Work {
  std::vector<double> element;  // E
  std::vector<double> node;     // N
};
Work work_of(const formats::Model& model, const simulator::Plan& plan, const CostModel& cost = {});

// Nodes of one neighbour part: sent to it or received from it each step, ascending ids.
struct Exchange {
  int part = 0;
  std::vector<Index> nodes;
};

struct Part {
  int index = 0;
  std::int64_t layer_begin = 0, layer_end = 0;  // owned node layers [begin, end) along the axis
  std::vector<Index> owned_nodes;               // ascending
  std::vector<Index> elements;                  // computed: every element touching an owned node
  std::vector<Index> primary_elements;          // elements whose base corner it owns (⊂ elements)
  std::vector<Index> halo_nodes;                // nodes of `elements` it does not own, ascending
  std::vector<Exchange> receives, sends;        // by neighbour part, ascending part index
  double work = 0;                              // CostModel units: owned nodes + computed elements
  std::size_t halo_elements() const { return elements.size() - primary_elements.size(); }
};

struct Partition {
  int axis = 0;  // lattice axis cut (0 = i/x, 1 = j/y, 2 = k/z)
  std::vector<Part> parts;
  std::vector<std::int32_t> node_owner;       // N, part owning each node
  std::vector<std::int32_t> element_primary;  // E, primary part of each element
  // max part work / mean part work (1 = perfect).
  double imbalance() const;
  // Bytes received by all parts together per step: 3 scalars of `scalar_bytes` per halo node.
  std::size_t bytes_per_step(std::size_t scalar_bytes) const;
  // The printable partition (sinew-simulate --explain --parts P).
  std::string explain(std::size_t scalar_bytes) const;
};

// Cuts the lattice into `parts` slabs along `axis` (−1: the axis with the most node layers),
// minimising the largest part's work. Throws ConfigError (field "parts") when parts < 1 or there
// are fewer node layers along the axis than parts, and (field "work") when the work vectors do not
// match the model.
Partition make_partition(const formats::Model& model, const Work& work, int parts, int axis = -1);

}  // namespace sinew::partition
