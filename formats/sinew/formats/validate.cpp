#include "sinew/formats/validate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "sinew/common/error.hpp"
#include "sinew/formats/sha256.hpp"

namespace sinew::formats {

namespace {

std::string show(const Lattice& l) {
  return fmt::format("({}, {}, {})", l[0], l[1], l[2]);
}
std::string show(const Point& p) {
  return fmt::format("({:.17g}, {:.17g}, {:.17g})", p[0], p[1], p[2]);
}

bool finite(const Point& p) {
  return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
}

class Validator {
 public:
  Validator(const Model& model, const std::string& file) : m_(model), file_(file) {}

  void run() {
    grid();
    elements_and_nodes();
    materials();
    element_materials();
    muscles();
    surfaces();
    constraints();
    jaw();
    sets(m_.node_sets, "/node_sets", m_.node_count(), "node");
    sets(m_.element_sets, "/element_sets", m_.element_count(), "element");
    provenance();
  }

 private:
  [[noreturn]] void fail(const std::string& dataset, std::int64_t index,
                         const std::string& problem) const {
    throw FormatError(file_, dataset, problem).at(index);
  }
  [[noreturn]] void fail(const std::string& dataset, const std::string& problem) const {
    throw FormatError(file_, dataset, problem);
  }

  // Materials, muscles and surfaces are looked up by name: non-empty and unique in their table.
  // Returns the "<kind> '<name>': " prefix of the entry's further messages.
  std::string unique_name(const std::string& dataset, std::int64_t index, const std::string& name,
                          const char* kind, std::set<std::string>& seen) const {
    if (name.empty()) fail(dataset, index, fmt::format("{} name is empty", kind));
    if (!seen.insert(name).second) {
      fail(dataset, index, fmt::format("duplicate {} name '{}'", kind, name));
    }
    return fmt::format("{} '{}': ", kind, name);
  }

  void check_size(const std::string& dataset, std::size_t got, std::size_t expected,
                  const std::string& what) const {
    if (got != expected) {
      fail(dataset, fmt::format("has {} rows, expected {} ({})", got, expected, what));
    }
  }

  // A fraction: finite and in [0, 1].
  void check_fraction(const std::string& dataset, std::int64_t index, double f,
                      const std::string& context) const {
    if (!std::isfinite(f))
      fail(dataset, index, fmt::format("{}fraction is not finite ({})", context, f));
    if (f < 0.0 || f > 1.0)
      fail(dataset, index, fmt::format("{}fraction {} outside [0, 1]", context, f));
  }

  void grid() {
    const auto& g = m_.grid;
    if (!finite(g.origin)) fail("/grid/origin", "origin is not finite: " + show(g.origin));
    if (!std::isfinite(g.voxel_size) || !(g.voxel_size > 0)) {
      fail("/grid/voxel_size",
           fmt::format("voxel size must be positive and finite, got {}", g.voxel_size));
    }
    for (int a = 0; a < 3; ++a) {
      if (g.dims[static_cast<std::size_t>(a)] < 1) {
        fail("/grid/dims", a,
             fmt::format("grid dimension must be at least 1, got {}",
                         g.dims[static_cast<std::size_t>(a)]));
      }
    }
  }

  void elements_and_nodes() {
    const auto& dims = m_.grid.dims;
    const auto& el = m_.element_lattice;
    const auto& nl = m_.node_lattice;
    if (el.empty()) fail("/elements/lattice", "the model has no elements");
    for (std::size_t e = 0; e < el.size(); ++e) {
      for (std::size_t a = 0; a < 3; ++a) {
        if (el[e][a] < 0 || el[e][a] >= dims[a]) {
          fail("/elements/lattice", static_cast<std::int64_t>(e),
               fmt::format("element base {} outside the grid of {} × {} × {} voxels", show(el[e]),
                           dims[0], dims[1], dims[2]));
        }
      }
      if (e > 0 && !lattice_less(el[e - 1], el[e])) {
        fail("/elements/lattice", static_cast<std::int64_t>(e),
             fmt::format("elements not sorted by (k, j, i) and unique: {} follows {}", show(el[e]),
                         show(el[e - 1])));
      }
    }
    for (std::size_t n = 0; n < nl.size(); ++n) {
      for (std::size_t a = 0; a < 3; ++a) {
        if (nl[n][a] < 0 || nl[n][a] > dims[a]) {
          fail("/nodes/lattice", static_cast<std::int64_t>(n),
               fmt::format("node lattice point {} outside the lattice [0, {}] × [0, {}] × [0, {}]",
                           show(nl[n]), dims[0], dims[1], dims[2]));
        }
      }
      if (n > 0 && !lattice_less(nl[n - 1], nl[n])) {
        fail("/nodes/lattice", static_cast<std::int64_t>(n),
             fmt::format("nodes not sorted by (k, j, i) and unique: {} follows {}", show(nl[n]),
                         show(nl[n - 1])));
      }
    }
    check_size("/elements/nodes", m_.element_nodes.size(), el.size(), "one row per element");
    std::vector<char> used(nl.size(), 0);
    for (std::size_t e = 0; e < el.size(); ++e) {
      for (std::size_t a = 0; a < 8; ++a) {
        const Index id = m_.element_nodes[e][a];
        if (id < 0 || static_cast<std::size_t>(id) >= nl.size()) {
          fail("/elements/nodes", static_cast<std::int64_t>(e),
               fmt::format("node id {} (corner {}) out of range [0, {})", id, a, nl.size()));
        }
        const Lattice expected{el[e][0] + kHexCorner[a][0], el[e][1] + kHexCorner[a][1],
                               el[e][2] + kHexCorner[a][2]};
        if (nl[static_cast<std::size_t>(id)] != expected) {
          fail("/elements/nodes", static_cast<std::int64_t>(e),
               fmt::format(
                   "corner {} is node {} at lattice {}, but base {} + corner offset gives {}", a,
                   id, show(nl[static_cast<std::size_t>(id)]), show(el[e]), show(expected)));
        }
        used[static_cast<std::size_t>(id)] = 1;
      }
    }
    for (std::size_t n = 0; n < nl.size(); ++n) {
      if (!used[n]) {
        fail("/nodes/lattice", static_cast<std::int64_t>(n),
             "node " + show(nl[n]) + " is not a corner of any element");
      }
    }
  }

  void materials() {
    const auto& ms = m_.materials;
    if (ms.empty()) fail("/materials/name", "the model has no materials");
    std::set<std::string> names;
    for (std::size_t i = 0; i < ms.size(); ++i) {
      const auto& mat = ms[i];
      const auto idx = static_cast<std::int64_t>(i);
      const std::string who = unique_name("/materials/name", idx, mat.name, "material", names);
      auto positive = [&](const char* dataset, double v, const char* what) {
        if (!std::isfinite(v) || !(v > 0)) {
          fail(dataset, idx, fmt::format("{}{} must be positive and finite, got {}", who, what, v));
        }
      };
      positive("/materials/youngs_modulus", mat.youngs_modulus, "Young's modulus");
      if (!std::isfinite(mat.poisson_ratio) || !(mat.poisson_ratio > -1.0) ||
          !(mat.poisson_ratio < 0.5)) {
        fail("/materials/poisson_ratio", idx,
             fmt::format("{}Poisson ratio {} outside (-1, 0.5)", who, mat.poisson_ratio));
      }
      positive("/materials/shear_modulus", mat.shear_modulus, "shear modulus");
      positive("/materials/bulk_modulus", mat.bulk_modulus, "bulk modulus");
      positive("/materials/density", mat.density, "density");
      const auto [mu, kappa] = shear_and_bulk_modulus(mat.youngs_modulus, mat.poisson_ratio);
      if (std::abs(mat.shear_modulus - mu) > kModulusRelativeTolerance * mu) {
        fail("/materials/shear_modulus", idx,
             fmt::format("{}shear modulus {} inconsistent with E/(2(1+nu)) = {}", who,
                         mat.shear_modulus, mu));
      }
      if (std::abs(mat.bulk_modulus - kappa) > kModulusRelativeTolerance * kappa) {
        fail("/materials/bulk_modulus", idx,
             fmt::format("{}bulk modulus {} inconsistent with E/(3(1-2nu)) = {}", who,
                         mat.bulk_modulus, kappa));
      }
    }
  }

  void element_materials() {
    const std::size_t e_count = m_.element_count();
    const auto& off = m_.material_offsets;
    check_size("/element_materials/offsets", off.size(), e_count + 1, "elements + 1");
    const std::size_t k = m_.material_ids.size();
    check_size("/element_materials/fraction", m_.material_fractions.size(), k,
               "as many as /element_materials/material");
    if (off[0] != 0)
      fail("/element_materials/offsets", 0, fmt::format("first offset must be 0, got {}", off[0]));
    for (std::size_t e = 0; e < e_count; ++e) {
      if (off[e + 1] < off[e]) {
        fail("/element_materials/offsets", static_cast<std::int64_t>(e + 1),
             fmt::format("offsets decrease: {} after {}", off[e + 1], off[e]));
      }
    }
    if (off[e_count] != static_cast<Offset>(k)) {
      fail("/element_materials/offsets", static_cast<std::int64_t>(e_count),
           fmt::format("last offset {} differs from the number of entries {}", off[e_count], k));
    }
    const std::size_t m_count = m_.materials.size();
    for (std::size_t e = 0; e < e_count; ++e) {
      double sum = 0;
      for (auto i = static_cast<std::size_t>(off[e]); i < static_cast<std::size_t>(off[e + 1]);
           ++i) {
        const Index mat = m_.material_ids[i];
        if (mat < 0 || static_cast<std::size_t>(mat) >= m_count) {
          fail("/element_materials/material", static_cast<std::int64_t>(i),
               fmt::format("element {}: material id {} out of range [0, {})", e, mat, m_count));
        }
        for (auto j = static_cast<std::size_t>(off[e]); j < i; ++j) {
          if (m_.material_ids[j] == mat) {
            fail("/element_materials/material", static_cast<std::int64_t>(i),
                 fmt::format("element {}: material {} listed twice", e, mat));
          }
        }
        check_fraction("/element_materials/fraction", static_cast<std::int64_t>(i),
                       m_.material_fractions[i], fmt::format("element {}: ", e));
        sum += m_.material_fractions[i];
      }
      if (!(sum > 0)) {
        fail("/element_materials/offsets", static_cast<std::int64_t>(e),
             fmt::format("element {} has no material (fraction sum {})", e, sum));
      }
      if (sum > 1.0 + kFractionSumTolerance) {
        fail("/element_materials/fraction", static_cast<std::int64_t>(off[e]),
             fmt::format("element {}: fraction sum {} exceeds 1", e, sum));
      }
    }
  }

  void muscles() {
    std::set<std::string> names;
    std::int64_t flat = 0;
    const std::size_t e_count = m_.element_count();
    for (std::size_t i = 0; i < m_.muscles.size(); ++i) {
      const auto& mu = m_.muscles[i];
      const auto idx = static_cast<std::int64_t>(i);
      const std::string who = unique_name("/muscles/name", idx, mu.name, "muscle", names);
      if (mu.material < 0 || static_cast<std::size_t>(mu.material) >= m_.materials.size()) {
        fail("/muscles/material", idx,
             fmt::format("{}material id {} out of range [0, {})", who, mu.material,
                         m_.materials.size()));
      }
      auto check = [&](const char* dataset, double v, bool ok, const char* rule) {
        if (!std::isfinite(v) || !ok)
          fail(dataset, idx, fmt::format("{}{} (got {})", who, rule, v));
      };
      check("/muscles/reference_stress", mu.reference_stress, mu.reference_stress >= 0,
            "reference stress must be finite and >= 0");
      check("/muscles/optimal_stretch", mu.optimal_stretch, mu.optimal_stretch > 0,
            "optimal fibre stretch must be finite and > 0");
      check("/muscles/passive_p1", mu.passive_p1, mu.passive_p1 >= 0,
            "passive p1 must be finite and >= 0");
      check("/muscles/passive_p2", mu.passive_p2, mu.passive_p2 >= 0,
            "passive p2 must be finite and >= 0");
      check("/muscles/passive_linear_stretch", mu.passive_linear_stretch,
            mu.passive_linear_stretch > 1, "passive linear stretch must be finite and > 1");
      if (mu.fractions.size() != mu.elements.size() || mu.fibres.size() != mu.elements.size()) {
        fail("/muscles/offsets", idx,
             fmt::format("{}{} elements but {} fractions and {} fibres", who, mu.elements.size(),
                         mu.fractions.size(), mu.fibres.size()));
      }
      for (std::size_t j = 0; j < mu.elements.size(); ++j, ++flat) {
        const Index e = mu.elements[j];
        if (e < 0 || static_cast<std::size_t>(e) >= e_count) {
          fail("/muscles/elements", flat,
               fmt::format("{}element id {} out of range [0, {})", who, e, e_count));
        }
        if (j > 0 && !(mu.elements[j - 1] < e)) {
          fail("/muscles/elements", flat,
               fmt::format("{}element ids not sorted and unique: {} follows {}", who, e,
                           mu.elements[j - 1]));
        }
        check_fraction("/muscles/fractions", flat, mu.fractions[j], who);
        const Point& f = mu.fibres[j];
        if (!finite(f)) fail("/muscles/fibres", flat, who + "fibre is not finite: " + show(f));
        const double len = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        if (std::abs(len - 1.0) > kUnitLengthTolerance) {
          fail("/muscles/fibres", flat,
               fmt::format("{}fibre direction is not a unit vector (length {})", who, len));
        }
      }
    }
  }

  void surfaces() {
    std::set<std::string> names;
    std::int64_t v_flat = 0, t_flat = 0, emb_flat = 0, uv_flat = 0, uvt_flat = 0;
    const std::size_t e_count = m_.element_count();
    for (std::size_t s = 0; s < m_.surfaces.size(); ++s) {
      const auto& sf = m_.surfaces[s];
      const auto idx = static_cast<std::int64_t>(s);
      const std::string who = unique_name("/surfaces/name", idx, sf.name, "surface", names);
      for (std::size_t v = 0; v < sf.vertices.size(); ++v) {
        if (!finite(sf.vertices[v])) {
          fail("/surfaces/vertices", v_flat + static_cast<std::int64_t>(v),
               who + "vertex is not finite: " + show(sf.vertices[v]));
        }
      }
      for (std::size_t t = 0; t < sf.triangles.size(); ++t) {
        const auto& tri = sf.triangles[t];
        for (const Index v : tri) {
          if (v < 0 || static_cast<std::size_t>(v) >= sf.vertices.size()) {
            fail("/surfaces/triangles", t_flat + static_cast<std::int64_t>(t),
                 fmt::format("{}vertex id {} out of range [0, {})", who, v, sf.vertices.size()));
          }
        }
        if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
          fail(
              "/surfaces/triangles", t_flat + static_cast<std::int64_t>(t),
              fmt::format("{}triangle ({}, {}, {}) repeats a vertex", who, tri[0], tri[1], tri[2]));
        }
      }
      if (sf.role == SurfaceRole::visual) {
        if (sf.embedding_element.size() != sf.vertices.size() ||
            sf.embedding_local.size() != sf.vertices.size()) {
          fail("/surfaces/embedding_offsets", idx,
               fmt::format("{}visual surface with {} vertices has {} embedding elements and {} "
                           "local coordinates (one per vertex expected)",
                           who, sf.vertices.size(), sf.embedding_element.size(),
                           sf.embedding_local.size()));
        }
        for (std::size_t v = 0; v < sf.vertices.size(); ++v) {
          const auto row = emb_flat + static_cast<std::int64_t>(v);
          const Index e = sf.embedding_element[v];
          if (e < 0 || static_cast<std::size_t>(e) >= e_count) {
            fail(
                "/surfaces/embedding_element", row,
                fmt::format("{}vertex {}: element id {} out of range [0, {})", who, v, e, e_count));
          }
          const Point& xi = sf.embedding_local[v];
          if (!finite(xi)) {
            fail("/surfaces/embedding_local", row,
                 fmt::format("{}vertex {}: local coordinates not finite {}", who, v, show(xi)));
          }
          for (const double c : xi) {
            if (c < -1.0 - kEmbeddingTolerance || c > 1.0 + kEmbeddingTolerance) {
              fail("/surfaces/embedding_local", row,
                   fmt::format("{}vertex {}: local coordinates {} outside the element [-1, 1]^3",
                               who, v, show(xi)));
            }
          }
        }
        emb_flat += static_cast<std::int64_t>(sf.vertices.size());
      } else if (!sf.embedding_element.empty() || !sf.embedding_local.empty()) {
        fail("/surfaces/embedding_offsets", idx,
             who + "only visual surfaces carry an embedding, this one has role " +
                 to_string(sf.role));
      }
      texture_coordinates(sf, idx, who, uv_flat, uvt_flat);
      v_flat += static_cast<std::int64_t>(sf.vertices.size());
      t_flat += static_cast<std::int64_t>(sf.triangles.size());
      uv_flat += static_cast<std::int64_t>(sf.uvs.size());
      uvt_flat += static_cast<std::int64_t>(sf.uv_triangles.size());
    }
  }

  // A surface's optional texture coordinates: visual surfaces only, none or one row of corner ids
  // per triangle, each id in range, every (u, v) finite. uv_flat, uvt_flat: rows of the surfaces
  // before this one in /surfaces/uvs and /surfaces/uv_triangles.
  void texture_coordinates(const Surface& sf, std::int64_t idx, const std::string& who,
                           std::int64_t uv_flat, std::int64_t uvt_flat) {
    if (sf.uvs.empty() && sf.uv_triangles.empty()) return;
    if (sf.role != SurfaceRole::visual) {
      fail("/surfaces/uv_offsets", idx,
           who + "only visual surfaces carry texture coordinates, this one has role " +
               to_string(sf.role));
    }
    if (sf.uv_triangles.size() != sf.triangles.size()) {
      fail("/surfaces/uv_triangle_offsets", idx,
           fmt::format("{}{} rows of texture corners for {} triangles (one per triangle expected)",
                       who, sf.uv_triangles.size(), sf.triangles.size()));
    }
    for (std::size_t i = 0; i < sf.uvs.size(); ++i) {
      const TexCoord& uv = sf.uvs[i];
      if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) {
        fail("/surfaces/uvs", uv_flat + static_cast<std::int64_t>(i),
             fmt::format("{}texture coordinate ({}, {}) is not finite", who, uv[0], uv[1]));
      }
    }
    for (std::size_t t = 0; t < sf.uv_triangles.size(); ++t) {
      for (const Index k : sf.uv_triangles[t]) {
        if (k < 0 || static_cast<std::size_t>(k) >= sf.uvs.size()) {
          fail("/surfaces/uv_triangles", uvt_flat + static_cast<std::int64_t>(t),
               fmt::format("{}texture coordinate id {} out of range [0, {})", who, k,
                           sf.uvs.size()));
        }
      }
    }
  }

  void constraints() {
    const std::size_t n_count = m_.node_count();
    const auto& rigid = m_.rigid_nodes;
    for (std::size_t i = 0; i < rigid.size(); ++i) {
      if (rigid[i] < 0 || static_cast<std::size_t>(rigid[i]) >= n_count) {
        fail("/constraints/rigid_nodes", static_cast<std::int64_t>(i),
             fmt::format("node id {} out of range [0, {})", rigid[i], n_count));
      }
      if (i > 0 && !(rigid[i - 1] < rigid[i])) {
        fail("/constraints/rigid_nodes", static_cast<std::int64_t>(i),
             fmt::format("node ids not sorted and unique: {} follows {}", rigid[i], rigid[i - 1]));
      }
    }
    for (std::size_t b = 0; b < m_.sliding.size(); ++b) {
      const auto& s = m_.sliding[b];
      const auto idx = static_cast<std::int64_t>(b);
      if (s.node < 0 || static_cast<std::size_t>(s.node) >= n_count) {
        fail("/constraints/sliding_node", idx,
             fmt::format("node id {} out of range [0, {})", s.node, n_count));
      }
      if (b > 0 && !(m_.sliding[b - 1].node < s.node)) {
        fail("/constraints/sliding_node", idx,
             fmt::format("sliding nodes not sorted and unique: {} follows {}", s.node,
                         m_.sliding[b - 1].node));
      }
      if (std::binary_search(rigid.begin(), rigid.end(), s.node)) {
        fail("/constraints/sliding_node", idx,
             fmt::format("node {} is both rigid and sliding", s.node));
      }
      if (s.surface < 0 || static_cast<std::size_t>(s.surface) >= m_.surfaces.size()) {
        fail("/constraints/sliding_surface", idx,
             fmt::format("surface id {} out of range [0, {})", s.surface, m_.surfaces.size()));
      }
      const auto& sf = m_.surfaces[static_cast<std::size_t>(s.surface)];
      if (sf.role != SurfaceRole::sliding) {
        fail("/constraints/sliding_surface", idx,
             fmt::format("surface {} ('{}') has role {}, expected sliding", s.surface, sf.name,
                         to_string(sf.role)));
      }
      if (!std::isfinite(s.rest_distance) || s.rest_distance < 0) {
        fail("/constraints/sliding_rest_distance", idx,
             fmt::format("rest distance must be finite and >= 0, got {}", s.rest_distance));
      }
      if (s.rest_triangle < 0 || static_cast<std::size_t>(s.rest_triangle) >= sf.triangles.size()) {
        fail("/constraints/sliding_rest_triangle", idx,
             fmt::format("triangle id {} out of range [0, {}) of surface '{}'", s.rest_triangle,
                         sf.triangles.size(), sf.name));
      }
    }
  }

  // The jaw: nodes in range, sorted, unique, neither rigid nor sliding; a finite frame of unit,
  // orthogonal axis and forward; finite pivot and incisal point.
  void jaw() {
    if (!m_.jaw) return;
    const Jaw& j = *m_.jaw;
    const std::size_t n_count = m_.node_count();
    if (j.nodes.empty()) fail("/jaw/nodes", "the jaw has no node");
    for (std::size_t i = 0; i < j.nodes.size(); ++i) {
      const auto idx = static_cast<std::int64_t>(i);
      const Index nd = j.nodes[i];
      if (nd < 0 || static_cast<std::size_t>(nd) >= n_count)
        fail("/jaw/nodes", idx, fmt::format("node id {} out of range [0, {})", nd, n_count));
      if (i > 0 && !(j.nodes[i - 1] < nd)) {
        fail("/jaw/nodes", idx,
             fmt::format("node ids not sorted and unique: {} follows {}", nd, j.nodes[i - 1]));
      }
      if (std::binary_search(m_.rigid_nodes.begin(), m_.rigid_nodes.end(), nd))
        fail("/jaw/nodes", idx, fmt::format("node {} is both rigid and on the jaw", nd));
      const auto bound =
          std::lower_bound(m_.sliding.begin(), m_.sliding.end(), nd,
                           [](const SlidingBinding& b, Index node) { return b.node < node; });
      if (bound != m_.sliding.end() && bound->node == nd)
        fail("/jaw/nodes", idx, fmt::format("node {} is both sliding and on the jaw", nd));
    }
    const auto finite = [&](const Point& p, const char* path) {
      for (double x : p)
        if (!std::isfinite(x))
          fail(path, fmt::format("not finite: ({}, {}, {})", p[0], p[1], p[2]));
    };
    const auto length = [](const Point& p) {
      return std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    };
    for (const auto& [p, path] :
         {std::pair{j.pivot, "/jaw/pivot"}, std::pair{j.axis, "/jaw/axis"},
          std::pair{j.forward, "/jaw/forward"}, std::pair{j.incisal, "/jaw/incisal"}})
      finite(p, path);
    for (const auto& [p, path] :
         {std::pair{j.axis, "/jaw/axis"}, std::pair{j.forward, "/jaw/forward"}}) {
      if (std::abs(length(p) - 1) > kUnitLengthTolerance)
        fail(path, fmt::format("not a unit vector: length {}", length(p)));
    }
    const double cosine =
        j.axis[0] * j.forward[0] + j.axis[1] * j.forward[1] + j.axis[2] * j.forward[2];
    if (std::abs(cosine) > kUnitLengthTolerance)
      fail("/jaw/forward", fmt::format("not normal to /jaw/axis: cosine {}", cosine));
    lip_pairs(j);
  }

  // The lips' pairs: node ids in range, two different nodes, each node in at most one pair, the
  // upper node above the lower one (along up = forward × axis) and not both held.
  void lip_pairs(const Jaw& j) {
    const std::size_t n_count = m_.node_count();
    const Point up{j.forward[1] * j.axis[2] - j.forward[2] * j.axis[1],
                   j.forward[2] * j.axis[0] - j.forward[0] * j.axis[2],
                   j.forward[0] * j.axis[1] - j.forward[1] * j.axis[0]};
    const auto held = [&](Index nd) {
      return std::binary_search(m_.rigid_nodes.begin(), m_.rigid_nodes.end(), nd) ||
             std::binary_search(j.nodes.begin(), j.nodes.end(), nd);
    };
    std::set<Index> seen;
    for (std::size_t i = 0; i < j.lip_pairs.size(); ++i) {
      const auto idx = static_cast<std::int64_t>(i);
      const auto [upper, lower] = j.lip_pairs[i];
      for (const Index nd : {upper, lower}) {
        if (nd < 0 || static_cast<std::size_t>(nd) >= n_count)
          fail("/jaw/lip_pairs", idx, fmt::format("node id {} out of range [0, {})", nd, n_count));
        if (!seen.insert(nd).second)
          fail("/jaw/lip_pairs", idx, fmt::format("node {} is in two pairs", nd));
      }
      if (held(upper) && held(lower))
        fail("/jaw/lip_pairs", idx,
             fmt::format("nodes {} and {} are both held (rigid or on the jaw)", upper, lower));
      const auto pu = m_.node_position(upper), pl = m_.node_position(lower);
      const double rise =
          (pu[0] - pl[0]) * up[0] + (pu[1] - pl[1]) * up[1] + (pu[2] - pl[2]) * up[2];
      if (!(rise > 0))
        fail("/jaw/lip_pairs", idx,
             fmt::format("the upper node {} is not above the lower node {} (up = forward × axis)",
                         upper, lower));
    }
  }

  void sets(const std::vector<NamedSet>& named, const std::string& group, std::size_t count,
            const char* kind) {
    std::set<std::string> names;
    for (std::size_t i = 0; i < named.size(); ++i) {
      const auto& set = named[i];
      if (!is_valid_set_name(set.name)) {
        fail(group, static_cast<std::int64_t>(i),
             "invalid set name '" + set.name +
                 "' (non-empty printable ASCII without '/', not '.' or '..')");
      }
      if (!names.insert(set.name).second) {
        fail(group, static_cast<std::int64_t>(i), "duplicate set name '" + set.name + "'");
      }
      const std::string dataset = group + "/" + set.name;
      for (std::size_t j = 0; j < set.ids.size(); ++j) {
        const Index id = set.ids[j];
        if (id < 0 || static_cast<std::size_t>(id) >= count) {
          fail(dataset, static_cast<std::int64_t>(j),
               fmt::format("{} id {} out of range [0, {})", kind, id, count));
        }
        if (j > 0 && !(set.ids[j - 1] < id)) {
          fail(
              dataset, static_cast<std::int64_t>(j),
              fmt::format("{} ids not sorted and unique: {} follows {}", kind, id, set.ids[j - 1]));
        }
      }
    }
  }

  void provenance() {
    const auto& p = m_.provenance;
    for (std::size_t i = 0; i < p.inputs.size(); ++i) {
      if (!is_sha256_hex(p.inputs[i].sha256)) {
        fail("/provenance/input_sha256", static_cast<std::int64_t>(i),
             "'" + p.inputs[i].sha256 + "' is not a SHA-256 digest (64 lowercase hex digits)");
      }
    }
    if (!p.parameters_json.empty() && !nlohmann::json::accept(p.parameters_json)) {
      fail("/provenance/parameters_json", "parameters are not a valid JSON document");
    }
  }

  const Model& m_;
  const std::string& file_;
};

}  // namespace

bool is_valid_set_name(const std::string& name) {
  if (name.empty() || name == "." || name == "..") return false;
  for (const char c : name) {
    if (c == '/' || c < 0x20 || c > 0x7e) return false;
  }
  return true;
}

void validate_model(const Model& model, const std::string& file) {
  Validator(model, file).run();
}

}  // namespace sinew::formats
