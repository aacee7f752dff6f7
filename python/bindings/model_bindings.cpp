// sinew.Model and sinew.voxelize: a model file's datasets as NumPy arrays (docs/model-format.md).
// Arrays that are stored contiguously in the model (element nodes, lattices, CSR fractions, set
// ids, surface vertices and triangles, muscle fibres) are read-only views kept alive by the Model;
// what must be computed or regrouped (rest positions, materials, sliding bindings) is a copy.
#include <pybind11/stl.h>

#include "bindings.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/summary.hpp"
#ifdef SINEW_PYTHON_WITH_VOXELIZER
#include "sinew/voxelizer/spec.hpp"
#include "sinew/voxelizer/voxelize.hpp"
#endif

namespace sinew::python {
namespace {

using formats::Index;
using formats::Model;

py::ssize_t rows(std::size_t n) {
  return static_cast<py::ssize_t>(n);
}

template <typename Row>
auto flat(const std::vector<Row>& v) {
  return v.empty() ? nullptr : v.front().data();
}

const Model& of(py::object self) {
  return *self.cast<PyModel&>().model;
}

py::dict surface_dict(const formats::Surface& s, py::handle base) {
  py::dict d;
  d["name"] = s.name;
  d["role"] = formats::to_string(s.role);
  d["vertices"] = view(flat(s.vertices), {rows(s.vertices.size()), 3}, base);
  d["triangles"] = view(flat(s.triangles), {rows(s.triangles.size()), 3}, base);
  d["embedding_element"] =
      view(s.embedding_element.data(), {rows(s.embedding_element.size())}, base);
  d["embedding_local"] = view(flat(s.embedding_local), {rows(s.embedding_local.size()), 3}, base);
  d["uvs"] = view(flat(s.uvs), {rows(s.uvs.size()), 2}, base);
  d["uv_triangles"] = view(flat(s.uv_triangles), {rows(s.uv_triangles.size()), 3}, base);
  return d;
}

py::dict sets_dict(const std::vector<formats::NamedSet>& sets, py::handle base) {
  py::dict d;
  for (const auto& s : sets) d[py::str(s.name)] = view(s.ids.data(), {rows(s.ids.size())}, base);
  return d;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<PyModel, std::shared_ptr<PyModel>> cls(m, "Model", R"doc(
A voxel finite-element model (docs/model-format.md), SI units: metres, pascals, kg/m³.

Made by Model.load(path), sinew.voxelize(spec) or Simulation.model. Immutable: arrays stored
contiguously in the model are read-only views (writing to one raises ValueError); nodes,
materials and sliding are copies.
)doc");
  cls.def_static(
         "load",
         [](const std::string& path) {
           auto model = without_gil([&] { return formats::read_model(path); });
           return std::make_shared<PyModel>(
               PyModel{std::make_shared<const Model>(std::move(model)), path, ""});
         },
         py::arg("path"),
         "Reads and validates a model file (sinew.FormatError / IoError naming the file and "
         "dataset).")
      .def(
          "save",
          [](PyModel& self, const std::string& path) {
            without_gil([&] { formats::write_model(*self.model, path); });
            self.path = path;
          },
          py::arg("path"),
          "Writes the model file (validated; written to a temporary name, renamed when complete).")
      .def_property_readonly(
          "path",
          [](const PyModel& s) {
            return s.path.empty() ? py::object(py::none()) : py::str(s.path);
          },
          "The file the model was read from or saved to; None for one only in memory.")
      .def_property_readonly("node_count", [](const PyModel& s) { return s.model->node_count(); })
      .def_property_readonly("element_count",
                             [](const PyModel& s) { return s.model->element_count(); })
      .def_property_readonly(
          "voxel_size", [](const PyModel& s) { return s.model->grid.voxel_size; }, "m")
      .def_property_readonly(
          "origin", [](const PyModel& s) { return s.model->grid.origin; },
          "m, the position of lattice point (0, 0, 0)")
      .def_property_readonly(
          "dims", [](const PyModel& s) { return s.model->grid.dims; }, "voxels along x, y, z")
      .def_property_readonly(
          "nodes",
          [](const PyModel& s) {
            const Model& model = *s.model;
            std::vector<double> p(3 * model.node_count());
            for (std::size_t n = 0; n < model.node_count(); ++n) {
              const auto x = model.node_position(static_cast<Index>(n));
              for (int k = 0; k < 3; ++k) p[3 * n + k] = x[k];
            }
            return take(std::move(p), {rows(model.node_count()), 3});
          },
          "N × 3 float64, m: the nodes' rest positions (a copy, computed from the lattice).")
      .def_property_readonly(
          "elements",
          [](py::object self) {
            const auto& e = of(self).element_nodes;
            return view(flat(e), {rows(e.size()), 8}, self);
          },
          "E × 8 int32: each element's node ids in hex8 (VTK) order (read-only view).")
      .def_property_readonly(
          "node_lattice",
          [](py::object self) {
            const auto& l = of(self).node_lattice;
            return view(flat(l), {rows(l.size()), 3}, self);
          },
          "N × 3 int32: lattice coordinates (i, j, k) of the nodes (read-only view).")
      .def_property_readonly(
          "element_lattice",
          [](py::object self) {
            const auto& l = of(self).element_lattice;
            return view(flat(l), {rows(l.size()), 3}, self);
          },
          "E × 3 int32: lattice coordinates of each element's base corner (read-only view).")
      .def_property_readonly(
          "materials",
          [](const PyModel& s) {
            py::list out;
            for (const auto& mat : s.model->materials) {
              py::dict d;
              d["name"] = mat.name;
              d["law"] = formats::to_string(mat.law);
              d["youngs_modulus"] = mat.youngs_modulus;
              d["poisson_ratio"] = mat.poisson_ratio;
              d["shear_modulus"] = mat.shear_modulus;
              d["bulk_modulus"] = mat.bulk_modulus;
              d["density"] = mat.density;
              out.append(d);
            }
            return out;
          },
          "The materials, in id order: name, law, youngs_modulus, poisson_ratio, shear_modulus, "
          "bulk_modulus (Pa) and density (kg/m³) each (a copy).")
      .def_property_readonly(
          "material_offsets",
          [](py::object self) {
            const auto& v = of(self).material_offsets;
            return view(v.data(), {rows(v.size())}, self);
          },
          "E + 1 int64: element e's material entries are [offsets[e], offsets[e + 1]) (view).")
      .def_property_readonly(
          "material_ids",
          [](py::object self) {
            const auto& v = of(self).material_ids;
            return view(v.data(), {rows(v.size())}, self);
          },
          "K int32: the material of each entry (view).")
      .def_property_readonly(
          "material_fractions",
          [](py::object self) {
            const auto& v = of(self).material_fractions;
            return view(v.data(), {rows(v.size())}, self);
          },
          "K float64: the volume fraction of each entry in its element, (0, 1] (view).")
      .def_property_readonly(
          "muscles",
          [](py::object self) {
            py::dict out;
            for (const auto& mu : of(self).muscles) {
              py::dict d;
              d["material"] = mu.material;
              d["reference_stress"] = mu.reference_stress;
              d["optimal_stretch"] = mu.optimal_stretch;
              d["force_length"] = formats::to_string(mu.force_length);
              d["passive_p1"] = mu.passive_p1;
              d["passive_p2"] = mu.passive_p2;
              d["passive_linear_stretch"] = mu.passive_linear_stretch;
              d["elements"] = view(mu.elements.data(), {rows(mu.elements.size())}, self);
              d["fractions"] = view(mu.fractions.data(), {rows(mu.fractions.size())}, self);
              d["fibres"] = view(flat(mu.fibres), {rows(mu.fibres.size()), 3}, self);
              out[py::str(mu.name)] = d;
            }
            return out;
          },
          "name → dict: material (its passive tissue), reference_stress (Pa), optimal_stretch, "
          "force_length, passive_p1/p2/linear_stretch, and per overlapped element elements "
          "(int32), fractions and unit fibres (K × 3) as read-only views.")
      .def_property_readonly(
          "rigid_nodes",
          [](py::object self) {
            const auto& v = of(self).rigid_nodes;
            return view(v.data(), {rows(v.size())}, self);
          },
          "int32, sorted: the nodes held at rest (view).")
      .def_property_readonly(
          "sliding",
          [](const PyModel& s) {
            const auto& b = s.model->sliding;
            std::vector<std::int32_t> node(b.size()), surface(b.size()), triangle(b.size());
            std::vector<double> distance(b.size());
            for (std::size_t i = 0; i < b.size(); ++i) {
              node[i] = b[i].node;
              surface[i] = b[i].surface;
              triangle[i] = b[i].rest_triangle;
              distance[i] = b[i].rest_distance;
            }
            py::dict d;
            d["node"] = take(std::move(node), {rows(b.size())});
            d["surface"] = take(std::move(surface), {rows(b.size())});
            d["rest_distance"] = take(std::move(distance), {rows(b.size())});
            d["rest_triangle"] = take(std::move(triangle), {rows(b.size())});
            return d;
          },
          "The sliding bindings as arrays (copies): node, surface (index into the model's "
          "surfaces), rest_distance (m), rest_triangle.")
      .def_property_readonly(
          "jaw",
          [](py::object self) -> py::object {
            const auto& jaw = of(self).jaw;
            if (!jaw) return py::none();
            py::dict d;
            d["nodes"] = view(jaw->nodes.data(), {rows(jaw->nodes.size())}, self);
            d["pivot"] = jaw->pivot;
            d["axis"] = jaw->axis;
            d["forward"] = jaw->forward;
            d["incisal"] = jaw->incisal;
            d["lip_pairs"] = view(flat(jaw->lip_pairs), {rows(jaw->lip_pairs.size()), 2}, self);
            return d;
          },
          "The mandible (nodes, pivot, axis, forward, incisal, lip_pairs), or None.")
      .def_property_readonly(
          "surfaces",
          [](py::object self) {
            py::dict out;
            for (const auto& s : of(self).surfaces) out[py::str(s.name)] = surface_dict(s, self);
            return out;
          },
          "name → dict: role ('sliding' or 'visual'), vertices (V × 3, m), triangles (T × 3), "
          "embedding_element, embedding_local, uvs, uv_triangles (read-only views).")
      .def_property_readonly(
          "node_sets", [](py::object self) { return sets_dict(of(self).node_sets, self); },
          "name → int32 node ids, sorted (views).")
      .def_property_readonly(
          "element_sets", [](py::object self) { return sets_dict(of(self).element_sets, self); },
          "name → int32 element ids, sorted (views).")
      .def_property_readonly(
          "provenance",
          [](const PyModel& s) {
            const auto& p = s.model->provenance;
            py::dict d;
            d["tool"] = p.tool;
            d["tool_version"] = p.tool_version;
            d["created"] = p.created;
            py::list inputs;
            for (const auto& f : p.inputs) inputs.append(py::make_tuple(f.path, f.sha256));
            d["inputs"] = inputs;
            d["parameters_json"] = p.parameters_json;
            return d;
          },
          "Who made the model from what: tool, tool_version, created, inputs (path, sha256), "
          "parameters_json.")
      .def(
          "summary",
          [](const PyModel& s) { return formats::summary_text(formats::summarize(*s.model)); },
          "The summary sinew-inspect prints (elements, nodes, materials, muscles, sets, ...).")
      .def(
          "summary_json",
          [](const PyModel& s) { return formats::summary_json(formats::summarize(*s.model)); },
          "The same as one JSON document (sinew-inspect --json).")
      .def_property_readonly(
          "voxelize_summary",
          [](const PyModel& s) {
            return s.voxelize_summary.empty() ? py::object(py::none())
                                              : py::str(s.voxelize_summary);
          },
          "sinew-voxelize --json's summary (JSON text) when sinew.voxelize made the model, "
          "else None.")
      .def("__repr__", [](const PyModel& s) {
        return "<sinew.Model " + std::to_string(s.model->element_count()) + " elements, " +
               std::to_string(s.model->node_count()) + " nodes" +
               (s.path.empty() ? std::string(", in memory") : ", " + s.path) + ">";
      });

  m.attr("has_voxelizer") =
#ifdef SINEW_PYTHON_WITH_VOXELIZER
      true;
#else
      false;
#endif
  m.def(
      "_voxelize",
      [](const std::string& text, const std::string& file, const std::string& output, int threads,
         bool force) {
#ifdef SINEW_PYTHON_WITH_VOXELIZER
        auto made = without_gil([&] {
          auto spec = voxelizer::parse_spec(text, file);
          voxelizer::VoxelizeOptions options;
          options.threads = threads;
          options.force = force;
          auto result = voxelizer::voxelize(spec, options);
          if (!output.empty()) {
            formats::write_model(result.model, output);
            result.summary.output = output;
          }
          return result;
        });
        return std::make_shared<PyModel>(
            PyModel{std::make_shared<const Model>(std::move(made.model)), output,
                    voxelizer::summary_json(made.summary)});
#else
        (void)text, (void)output, (void)threads, (void)force;
        throw ConfigError(file, "",
                          "this sinew was built without the voxelizer "
                          "(SINEW_WITH_VOXELIZER=OFF)");
#endif
      },
      py::arg("text"), py::arg("file"), py::arg("output"), py::arg("threads"), py::arg("force"));
}

}  // namespace sinew::python
