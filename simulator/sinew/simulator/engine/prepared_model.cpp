#include "sinew/simulator/engine/prepared_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sinew/common/error.hpp"

namespace sinew::simulator {

PreparedModel prepare_model(const formats::Model& model, const Setup& setup, const Plan& plan) {
  PreparedModel p;
  const Effects& fx = setup.effects;
  p.nodes = model.node_count();
  p.elements = model.element_count();
  const std::size_t n = p.nodes, e_count = p.elements;
  p.h = model.grid.voxel_size;
  p.element_nodes = model.element_nodes;
  p.row = plan.parameter_row;
  for (const auto& r : plan.parameters)
    p.rows.push_back({fx.elasticity ? r.mu : 0.0, fx.elasticity ? r.kappa : 0.0, r.hourglass_k});
  p.rest.resize(n);
  for (std::size_t i = 0; i < n; ++i) p.rest[i] = model.node_position(Index(i));
  p.dominant_material.assign(e_count, 0);
  for (std::size_t e = 0; e < e_count; ++e) {
    double best = -1;
    for (auto k = model.material_offsets[e]; k < model.material_offsets[e + 1]; ++k)
      if (model.material_fractions[std::size_t(k)] > best) {
        best = model.material_fractions[std::size_t(k)];
        p.dominant_material[e] = model.material_ids[std::size_t(k)];
      }
  }
  p.mass.assign(n, 0.0);
  const double v0 = p.h * p.h * p.h;
  double min_modulus = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < e_count; ++e) {
    const auto& r = plan.parameters[std::size_t(p.row[e])];
    for (int a = 0; a < 8; ++a)
      p.mass[std::size_t(p.element_nodes[e][std::size_t(a)])] += r.density * v0 / 8;
    p.volume += v0;
    if (r.p_wave > 0) min_modulus = std::min(min_modulus, r.p_wave);
  }
  p.min_modulus = std::isfinite(min_modulus) ? min_modulus : 1.0;
  if (fx.gravity) {
    p.gravity.assign(n, {0, 0, 0});
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t k = 0; k < 3; ++k)
        p.gravity[i][k] = p.mass[i] / setup.mass_scaling * setup.gravity[k];
  }
  p.incidence_offset.assign(n + 1, 0);
  for (std::size_t e = 0; e < e_count; ++e)
    for (int a = 0; a < 8; ++a)
      ++p.incidence_offset[std::size_t(p.element_nodes[e][std::size_t(a)]) + 1];
  for (std::size_t i = 0; i < n; ++i) p.incidence_offset[i + 1] += p.incidence_offset[i];
  p.incidence.resize(e_count * 8);
  {
    std::vector<std::int64_t> fill(p.incidence_offset.begin(), p.incidence_offset.end() - 1);
    for (std::size_t e = 0; e < e_count; ++e)
      for (int a = 0; a < 8; ++a)
        p.incidence[std::size_t(fill[std::size_t(p.element_nodes[e][std::size_t(a)])]++)] =
            std::int32_t(e * 8 + std::size_t(a));
  }
  if (fx.muscles) {
    p.muscle_offset.assign(e_count + 1, 0);
    for (const auto& m : model.muscles)
      for (auto e : m.elements) ++p.muscle_offset[std::size_t(e) + 1];
    for (std::size_t e = 0; e < e_count; ++e) p.muscle_offset[e + 1] += p.muscle_offset[e];
    const auto total = std::size_t(p.muscle_offset[e_count]);
    p.muscle_id.resize(total);
    p.muscle_fraction.resize(total);
    p.muscle_fibre.resize(total);
    std::vector<std::int64_t> fill(p.muscle_offset.begin(), p.muscle_offset.end() - 1);
    for (std::size_t m = 0; m < model.muscles.size(); ++m) {
      const auto& mu = model.muscles[m];
      const double a_max = setup.max_activation(m);
      for (std::size_t i = 0; i < mu.elements.size(); ++i) {
        const auto k = std::size_t(fill[std::size_t(mu.elements[i])]++);
        p.muscle_id[k] = std::int32_t(m);
        p.muscle_fraction[k] = mu.fractions[i];
        const auto& f = mu.fibres[i];
        const double len = std::hypot(f[0], f[1], f[2]);
        if (!(len > 0))
          throw ConfigError("", "model.muscles.fibres",
                            "zero fibre direction in muscle '" + mu.name + "'")
              .at(std::int64_t(i));
        p.muscle_fibre[k] = {f[0] / len, f[1] / len, f[2] / len};
        p.active_energy_bound +=
            mu.fractions[i] * v0 * mu.reference_stress * mu.optimal_stretch * a_max * 0.6;
      }
      p.muscle_params.push_back({mu.reference_stress, mu.optimal_stretch, mu.passive_p1,
                                 mu.passive_p2, mu.passive_linear_stretch});
    }
  }
  if (fx.loads) {
    for (const auto& f : setup.forces) {
      PreparedLoadSet s;
      s.nodes = f.nodes;
      const double k = 1.0 / double(f.nodes.size());
      s.per_node = {f.total[0] * k, f.total[1] * k, f.total[2] * k};
      s.curve = f.curve;
      p.forces.push_back(std::move(s));
    }
    // Live force slots: empty and off (curve 0) until BackendCore::set_force_slot.
    for (int k = 0; k < setup.force_slots; ++k) {
      PreparedLoadSet s;
      s.curve = Curve::constant(0.0);
      p.forces.push_back(std::move(s));
    }
    for (const auto& pd : setup.prescribed) {
      PreparedLoadSet s;
      s.nodes = pd.nodes;
      s.per_node = pd.value;
      s.components = pd.components;
      s.curve = pd.curve;
      p.prescribed.push_back(std::move(s));
    }
  }
  for (const auto& pl : setup.sliding_planes) {
    const double len = std::hypot(pl.normal[0], pl.normal[1], pl.normal[2]);
    for (auto nd : pl.nodes) {
      p.plane_nodes.push_back(nd);
      p.plane_normals.push_back({pl.normal[0] / len, pl.normal[1] / len, pl.normal[2] / len});
    }
  }
  p.rigid = setup.rigid_nodes;
  if (setup.jaw) p.jaw_nodes = setup.jaw->nodes;
  if (setup.lip_contact) {
    // Held: rigid (the closed jaw's nodes among them) or moved by the jaw.
    const auto held = [&](Index nd) {
      return std::binary_search(p.rigid.begin(), p.rigid.end(), nd) ||
             std::binary_search(p.jaw_nodes.begin(), p.jaw_nodes.end(), nd);
    };
    for (const auto& [upper, lower] : setup.lip_contact->pairs) {
      const bool hu = held(upper), hl = held(lower);
      if (!hu) {
        p.contact_node.push_back(upper);
        p.contact_partner.push_back(lower);
        p.contact_share.push_back(hl ? 1.0 : 0.5);
      }
      if (!hl) {
        p.contact_node.push_back(lower);
        p.contact_partner.push_back(upper);
        p.contact_share.push_back(hu ? -1.0 : -0.5);
      }
    }
    const auto& up = setup.lip_contact->up;
    p.contact_up = {up[0], up[1], up[2]};
  }
  if (fx.sliding && !model.sliding.empty()) {
    std::vector<std::int32_t> local(model.surfaces.size(), -1);
    for (const auto& b : model.sliding) {
      auto& l = local[std::size_t(b.surface)];
      if (l < 0) {
        const auto& s = model.surfaces[std::size_t(b.surface)];
        PreparedSurface surf;
        surf.name = s.name;
        surf.vertices = s.vertices;
        for (const auto& t : s.triangles) {
          for (int c = 0; c < 3; ++c)
            if (t[std::size_t(c)] < 0 || std::size_t(t[std::size_t(c)]) >= s.vertices.size())
              throw ConfigError("", "model.surfaces.triangles",
                                "vertex id out of range in surface '" + s.name + "'");
          surf.triangles.push_back({t[0], t[1], t[2]});
        }
        surf.grid = build_surface_grid(s.vertices, surf.triangles);
        l = std::int32_t(p.surfaces.size());
        p.surfaces.push_back(std::move(surf));
      }
      p.slide_node.push_back(b.node);
      p.slide_surface.push_back(l);
      p.slide_distance.push_back(b.rest_distance);
      p.slide_triangle.push_back(b.rest_triangle);
    }
  }
  return p;
}

}  // namespace sinew::simulator
