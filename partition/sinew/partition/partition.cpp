#include "sinew/partition/partition.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <limits>

#include "sinew/common/error.hpp"

namespace sinew::partition {
namespace {

// Work of node layers [c, d) and the elements touching them (element bases c − 1 … d − 1), from
// prefix sums over node layers (node_prefix) and element base layers (element_prefix).
struct LayerWork {
  std::vector<double> node_prefix, element_prefix;  // L + 1 each
  std::int64_t layers() const { return std::int64_t(node_prefix.size()) - 1; }
  double of(std::int64_t c, std::int64_t d) const {
    const std::int64_t eb = std::max<std::int64_t>(c - 1, 0);
    const std::int64_t ee = std::min<std::int64_t>(d, layers() - 1);  // last base layer + 1
    const double elements =
        ee > eb ? element_prefix[std::size_t(ee)] - element_prefix[std::size_t(eb)] : 0.0;
    return node_prefix[std::size_t(d)] - node_prefix[std::size_t(c)] + elements;
  }
};

// Greedy cuts under a bound on each part's work, every part at least one layer: the cut layers
// (parts + 1 of them), or empty when the last part exceeds the bound.
std::vector<std::int64_t> cuts_under(const LayerWork& w, int parts, double bound) {
  const std::int64_t layers = w.layers();
  std::vector<std::int64_t> cuts{0};
  std::int64_t c = 0;
  for (int p = 0; p + 1 < parts; ++p) {
    std::int64_t d = c + 1;
    const std::int64_t last = layers - (parts - p - 1);  // leave a layer for each later part
    while (d < last && w.of(c, d + 1) <= bound) ++d;
    cuts.push_back(d);
    c = d;
  }
  cuts.push_back(layers);
  if (w.of(c, layers) > bound) return {};
  return cuts;
}

}  // namespace

Work work_of(const formats::Model& model, const simulator::Plan& plan, const CostModel& cost) {
  Work w;
  w.element.assign(model.element_count(), cost.element);
  for (const auto& c : plan.collections) {
    double each = c.multi_material ? cost.multi_material : cost.element;
    if (c.muscle) each *= cost.muscle;
    for (Index e : c.elements) w.element[std::size_t(e)] = each;
  }
  w.node.assign(model.node_count(), cost.node);
  if (plan.effects.sliding)
    for (const auto& b : model.sliding) w.node[std::size_t(b.node)] += cost.sliding_node;
  return w;
}

double Partition::imbalance() const {
  double total = 0, worst = 0;
  for (const auto& p : parts) {
    total += p.work;
    worst = std::max(worst, p.work);
  }
  return parts.empty() || total <= 0 ? 1.0 : worst * double(parts.size()) / total;
}

std::size_t Partition::bytes_per_step(std::size_t scalar_bytes) const {
  std::size_t halo = 0;
  for (const auto& p : parts) halo += p.halo_nodes.size();
  return halo * 3 * scalar_bytes;
}

std::string Partition::explain(std::size_t scalar_bytes) const {
  static const char* kAxis[] = {"i (x)", "j (y)", "k (z)"};
  std::string s =
      fmt::format("Partition: {} parts, slabs along lattice axis {}\n", parts.size(), kAxis[axis]);
  s += fmt::format("  {:>4}  {:>13}  {:>10}  {:>10}  {:>10}  {:>10}  {:>12}  {:>7}\n", "part",
                   "node layers", "nodes", "elements", "halo elem", "halo nodes", "recv B/step",
                   "work");
  double mean = 0;
  for (const auto& p : parts) mean += p.work / double(parts.size());
  for (const auto& p : parts)
    s += fmt::format("  {:>4}  {:>6}-{:<6}  {:>10}  {:>10}  {:>10}  {:>10}  {:>12}  {:>6.3f}\n",
                     p.index, p.layer_begin, p.layer_end - 1, p.owned_nodes.size(),
                     p.elements.size(), p.halo_elements(), p.halo_nodes.size(),
                     p.halo_nodes.size() * 3 * scalar_bytes, mean > 0 ? p.work / mean : 1.0);
  s += fmt::format(
      "  exchanged per step: {} bytes (u(n+1) of every halo node, {}-byte scalars); imbalance "
      "(max/mean work) {:.3f}\n",
      bytes_per_step(scalar_bytes), scalar_bytes, imbalance());
  return s;
}

Partition make_partition(const formats::Model& model, const Work& work, int parts, int axis) {
  const std::size_t n = model.node_count(), e_count = model.element_count();
  if (work.node.size() != n || work.element.size() != e_count)
    throw ConfigError("", "work",
                      fmt::format("{} node and {} element costs for a model of {} nodes and {} "
                                  "elements",
                                  work.node.size(), work.element.size(), n, e_count));
  if (parts < 1) throw ConfigError("", "parts", fmt::format("{} parts: need at least 1", parts));
  if (n == 0) throw ConfigError("", "parts", "the model has no nodes to partition");
  std::array<std::int64_t, 3> lo{}, hi{};
  lo.fill(std::numeric_limits<std::int64_t>::max());
  hi.fill(std::numeric_limits<std::int64_t>::min());
  for (const auto& l : model.node_lattice)
    for (std::size_t a = 0; a < 3; ++a) {
      lo[a] = std::min<std::int64_t>(lo[a], l[a]);
      hi[a] = std::max<std::int64_t>(hi[a], l[a]);
    }
  if (axis < 0) {
    axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[std::size_t(a)] - lo[std::size_t(a)] > hi[std::size_t(axis)] - lo[std::size_t(axis)])
        axis = a;
  }
  if (axis > 2) throw ConfigError("", "axis", fmt::format("axis {} is not 0, 1 or 2", axis));
  const std::size_t ax = std::size_t(axis);
  const std::int64_t layers = hi[ax] - lo[ax] + 1;
  if (layers < parts)
    throw ConfigError("", "parts",
                      fmt::format("{} parts but only {} node layers along lattice axis {}: at "
                                  "most {} parts",
                                  parts, layers, axis, layers));
  auto layer_of = [&](Index node) { return model.node_lattice[std::size_t(node)][ax] - lo[ax]; };

  LayerWork lw;
  lw.node_prefix.assign(std::size_t(layers) + 1, 0.0);
  lw.element_prefix.assign(std::size_t(layers) + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i)
    lw.node_prefix[std::size_t(layer_of(Index(i))) + 1] += work.node[i];
  for (std::size_t e = 0; e < e_count; ++e)
    lw.element_prefix[std::size_t(layer_of(model.element_nodes[e][0])) + 1] += work.element[e];
  for (std::size_t l = 0; l < std::size_t(layers); ++l) {
    lw.node_prefix[l + 1] += lw.node_prefix[l];
    lw.element_prefix[l + 1] += lw.element_prefix[l];
  }

  // The smallest bound on a part's work that the greedy cuts meet (bisection on the bound).
  double low = 0, high = lw.of(0, layers);
  std::vector<std::int64_t> cuts = cuts_under(lw, parts, high);
  for (int it = 0; it < 100 && high - low > 1e-9 * high; ++it) {
    const double mid = 0.5 * (low + high);
    auto c = cuts_under(lw, parts, mid);
    if (c.empty()) {
      low = mid;
    } else {
      high = mid;
      cuts = std::move(c);
    }
  }

  Partition out;
  out.axis = axis;
  out.parts.resize(std::size_t(parts));
  out.node_owner.assign(n, 0);
  std::vector<std::int32_t> layer_part(std::size_t(layers), 0);
  for (int p = 0; p < parts; ++p) {
    Part& part = out.parts[std::size_t(p)];
    part.index = p;
    part.layer_begin = cuts[std::size_t(p)] + lo[ax];
    part.layer_end = cuts[std::size_t(p) + 1] + lo[ax];
    for (std::int64_t l = cuts[std::size_t(p)]; l < cuts[std::size_t(p) + 1]; ++l)
      layer_part[std::size_t(l)] = p;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int p = layer_part[std::size_t(layer_of(Index(i)))];
    out.node_owner[i] = p;
    out.parts[std::size_t(p)].owned_nodes.push_back(Index(i));
    out.parts[std::size_t(p)].work += work.node[i];
  }
  // Elements: computed by every part owning one of its nodes; primary for its base corner's owner.
  out.element_primary.assign(e_count, 0);
  std::vector<std::vector<char>> halo_flag(std::size_t(parts), std::vector<char>(n, 0));
  for (std::size_t e = 0; e < e_count; ++e) {
    const auto& en = model.element_nodes[e];
    std::int32_t seen[8];
    int count = 0;
    for (Index v : en) {
      const std::int32_t p = out.node_owner[std::size_t(v)];
      if (std::find(seen, seen + count, p) == seen + count) seen[count++] = p;
    }
    out.element_primary[e] = out.node_owner[std::size_t(en[0])];
    for (int k = 0; k < count; ++k) {
      Part& part = out.parts[std::size_t(seen[k])];
      part.elements.push_back(Index(e));
      part.work += work.element[e];
      if (seen[k] == out.element_primary[e]) part.primary_elements.push_back(Index(e));
      for (Index v : en)
        if (out.node_owner[std::size_t(v)] != seen[k])
          halo_flag[std::size_t(seen[k])][std::size_t(v)] = 1;
    }
  }
  for (auto& part : out.parts) {
    auto& flags = halo_flag[std::size_t(part.index)];
    std::vector<std::vector<Index>> from(static_cast<std::size_t>(parts));
    for (std::size_t i = 0; i < n; ++i)
      if (flags[i]) {
        part.halo_nodes.push_back(Index(i));
        from[std::size_t(out.node_owner[i])].push_back(Index(i));
      }
    for (int q = 0; q < parts; ++q)
      if (!from[std::size_t(q)].empty()) {
        part.receives.push_back({q, from[std::size_t(q)]});
        out.parts[std::size_t(q)].sends.push_back({part.index, std::move(from[std::size_t(q)])});
      }
  }
  for (auto& part : out.parts)
    std::sort(part.sends.begin(), part.sends.end(),
              [](const Exchange& a, const Exchange& b) { return a.part < b.part; });
  return out;
}

}  // namespace sinew::partition
