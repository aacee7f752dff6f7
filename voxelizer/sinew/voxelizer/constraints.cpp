#include "sinew/voxelizer/constraints.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace sinew::voxelizer {

namespace {

Vec3d position(const formats::Model& model, std::size_t n) {
  const auto p = model.node_position(static_cast<formats::Index>(n));
  return {p[0], p[1], p[2]};
}

constexpr int kBlockShift = 3;  // node blocks of 8³ lattice points

// Nodes grouped by lattice block (blocks in lattice order, nodes ascending inside each), so a
// surface query at a block's centre can settle all its nodes at once (signed distance is
// 1-Lipschitz).
struct NodeBlocks {
  std::vector<std::int64_t> offsets;  // blocks + 1
  std::vector<formats::Index> nodes;
  std::vector<Vec3d> centres;
  double radius = 0;  // m, farthest node from its block's centre
};

NodeBlocks group_nodes(const formats::Model& model) {
  NodeBlocks b;
  const std::size_t nn = model.node_count();
  std::vector<std::pair<std::array<std::int32_t, 3>, formats::Index>> keyed(nn);
  for (std::size_t n = 0; n < nn; ++n) {
    const auto& l = model.node_lattice[n];
    keyed[n] = {{l[2] >> kBlockShift, l[1] >> kBlockShift, l[0] >> kBlockShift},
                static_cast<formats::Index>(n)};
  }
  std::sort(keyed.begin(), keyed.end());
  const double h = model.grid.voxel_size;
  const double half = 0.5 * ((1 << kBlockShift) - 1);
  b.radius = half * std::sqrt(3.0) * h;
  for (std::size_t q = 0; q < nn; ++q) {
    if (q == 0 || keyed[q].first != keyed[q - 1].first) {
      b.offsets.push_back(static_cast<std::int64_t>(q));
      const auto& k = keyed[q].first;
      const double s = 1 << kBlockShift;
      b.centres.push_back({model.grid.origin[0] + h * (k[2] * s + half),
                           model.grid.origin[1] + h * (k[1] * s + half),
                           model.grid.origin[2] + h * (k[0] * s + half)});
    }
    b.nodes.push_back(keyed[q].second);
  }
  b.offsets.push_back(static_cast<std::int64_t>(nn));
  return b;
}

}  // namespace

bool condition_selects(const BoundaryCondition& cond, const Vec3d& p) {
  if (cond.box && !cond.box->contains(p)) return false;
  if (!cond.surface) return true;
  if (cond.inside && cond.surface->inside(p)) return true;
  return cond.within && cond.surface->distance().distance(p) <= *cond.within;
}

ConstraintResult bind_constraints(const formats::Model& model,
                                  const std::vector<BoundaryCondition>& conditions) {
  const std::size_t nn = model.node_count();
  const NodeBlocks blocks = group_nodes(model);
  const auto nb = static_cast<std::int64_t>(blocks.centres.size());
  const double h = model.grid.voxel_size;
  // Per node: which condition binds it (-1 none), and the sliding data.
  std::vector<int> which(nn, -1);
  std::vector<double> rest(nn, 0.0);
  std::vector<std::int32_t> tri(nn, -1);
  for (std::size_t c = 0; c < conditions.size(); ++c) {
    const auto& cond = conditions[c];
    auto bind_node = [&](std::size_t n, bool known_selected) {
      if (which[n] >= 0) return;
      const Vec3d p = position(model, n);
      if (cond.box && !cond.box->contains(p)) return;
      bool selected = !cond.surface || known_selected;
      DistanceQuery::Hit hit{};
      bool have_hit = false;
      if (!selected) {
        if (cond.inside && cond.surface->inside(p)) selected = true;
        if (!selected && cond.within) {
          hit = cond.surface->distance().closest(p);
          have_hit = true;
          selected = hit.distance <= *cond.within;
        }
      }
      if (!selected) return;
      which[n] = static_cast<int>(c);
      if (cond.kind == BoundarySpec::Kind::sliding) {
        if (!have_hit) hit = cond.surface->distance().closest(p);
        rest[n] = hit.distance;
        tri[n] = hit.triangle;
      }
    };
    // What a cell's centre says for all its nodes: 0 none selected, 1 all selected by `inside`,
    // 2 undecided (split the cell, or decide per node).
    auto verdict = [&](const Vec3d& centre, double r) {
      const auto s = (*cond.surface)(centre);
      int v = 2;
      if (s.value + r < 0 && (!cond.within || -s.value - r > *cond.within)) v = 0;
      if (cond.inside && s.value - r > 0) v = 1;
      if (!cond.inside && cond.within && s.value - r > *cond.within) v = 0;
      if (!cond.surface->closed() && v != 2 && s.winding > 0.1 && s.winding < 0.9) v = 2;
      return v;
    };
    // Recursive halving of a block's lattice cube [lo, lo + size)³ over its nodes.
    std::function<void(std::vector<formats::Index>&, std::array<std::int32_t, 3>, int)> cell =
        [&](std::vector<formats::Index>& nodes, std::array<std::int32_t, 3> lo, int size) {
          if (nodes.empty()) return;
          if (!cond.surface || size == 1 || nodes.size() <= 2) {
            for (auto n : nodes) bind_node(static_cast<std::size_t>(n), false);
            return;
          }
          const double half = 0.5 * (size - 1);
          const Vec3d centre{model.grid.origin[0] + h * (lo[0] + half),
                             model.grid.origin[1] + h * (lo[1] + half),
                             model.grid.origin[2] + h * (lo[2] + half)};
          const int v = verdict(centre, half * std::sqrt(3.0) * h);
          if (v == 0) return;
          if (v == 1) {
            for (auto n : nodes) bind_node(static_cast<std::size_t>(n), true);
            return;
          }
          const int m = size / 2;
          std::vector<formats::Index> part[8];
          for (auto n : nodes) {
            const auto& l = model.node_lattice[static_cast<std::size_t>(n)];
            const int k = (l[0] - lo[0] >= m ? 1 : 0) | (l[1] - lo[1] >= m ? 2 : 0) |
                          (l[2] - lo[2] >= m ? 4 : 0);
            part[k].push_back(n);
          }
          for (int k = 0; k < 8; ++k) {
            cell(part[k],
                 {lo[0] + ((k & 1) ? m : 0), lo[1] + ((k & 2) ? m : 0), lo[2] + ((k & 4) ? m : 0)},
                 m);
          }
        };
#pragma omp parallel for schedule(dynamic, 4)
    for (std::int64_t b = 0; b < nb; ++b) {
      const auto first = blocks.offsets[static_cast<std::size_t>(b)];
      const auto last = blocks.offsets[static_cast<std::size_t>(b) + 1];
      std::vector<formats::Index> nodes(blocks.nodes.begin() + first, blocks.nodes.begin() + last);
      const auto& l = model.node_lattice[static_cast<std::size_t>(nodes.front())];
      const std::array<std::int32_t, 3> lo{(l[0] >> kBlockShift) << kBlockShift,
                                           (l[1] >> kBlockShift) << kBlockShift,
                                           (l[2] >> kBlockShift) << kBlockShift};
      cell(nodes, lo, 1 << kBlockShift);
    }
  }
  ConstraintResult out;
  out.per_condition.assign(conditions.size(), 0);
  out.condition.assign(which.begin(), which.end());
  for (std::size_t n = 0; n < nn; ++n) {
    const int c = which[n];
    if (c < 0) continue;
    ++out.per_condition[static_cast<std::size_t>(c)];
    const auto& cond = conditions[static_cast<std::size_t>(c)];
    if (cond.kind == BoundarySpec::Kind::rigid) {
      out.rigid.push_back(static_cast<formats::Index>(n));
    } else {
      out.sliding.push_back({static_cast<formats::Index>(n), cond.surface_index, rest[n], tri[n]});
    }
  }
  return out;
}

formats::NamedSet select_nodes(const formats::Model& model, const std::string& name,
                               const std::optional<Box>& box, const SignedField* surface,
                               double distance) {
  const std::size_t nn = model.node_count();
  const NodeBlocks blocks = group_nodes(model);
  const auto nb = static_cast<std::int64_t>(blocks.centres.size());
  std::vector<char> in(nn, 0);
#pragma omp parallel for schedule(dynamic, 16)
  for (std::int64_t b = 0; b < nb; ++b) {
    if (surface &&
        surface->distance().distance(blocks.centres[static_cast<std::size_t>(b)]) - blocks.radius >
            distance) {
      continue;
    }
    for (auto q = blocks.offsets[static_cast<std::size_t>(b)];
         q < blocks.offsets[static_cast<std::size_t>(b) + 1]; ++q) {
      const auto n = static_cast<std::size_t>(blocks.nodes[static_cast<std::size_t>(q)]);
      const Vec3d p = position(model, n);
      if (box && !box->contains(p)) continue;
      if (surface && surface->distance().distance(p) > distance) continue;
      in[n] = 1;
    }
  }
  formats::NamedSet set;
  set.name = name;
  for (std::size_t n = 0; n < nn; ++n)
    if (in[n]) set.ids.push_back(static_cast<formats::Index>(n));
  return set;
}

}  // namespace sinew::voxelizer
