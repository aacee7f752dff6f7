// sinew.Scene: a scene (docs/scene-format.md) read, validated and edited with the YAML reader the
// tools use, so a Python scene is refused with sinew-simulate's own message. Editing substitutes
// values at key paths (YamlNode::replaced, as sinew-sweep does) and parses the result again.
#include <pybind11/stl.h>

#include <filesystem>

#include "bindings.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/simulator/run/run_setup.hpp"

namespace sinew::python {

std::string scene_name(const PyScene& scene) {
  return scene.file.empty() ? "scene (from a dict)" : scene.file;
}

std::optional<simulator::Precision> precision_from(const py::object& name) {
  if (name.is_none()) return std::nullopt;
  const auto text = py::str(name).cast<std::string>();
  if (text == "float") return simulator::Precision::float32;
  if (text == "double") return simulator::Precision::float64;
  throw ConfigError("", "precision",
                    "expected 'float' or 'double' (or None: the scene's), got '" + text + "'");
}

namespace {

PyScene make_scene(std::string text, std::string file, std::string directory) {
  PyScene s{std::move(text), std::move(file), std::move(directory), {}};
  s.scene = simulator::parse_scene_text(s.text, scene_name(s), s.directory);
  return s;
}

// The scene with each (key path, value as YAML/JSON text) substituted. A problem the new values
// cause is reported as the scene reader words it, with the substitution that caused it.
PyScene replaced(const PyScene& base,
                 const std::vector<std::pair<std::string, std::string>>& values) {
  const std::string name = scene_name(base);
  std::string what;
  for (const auto& [path, value] : values)
    what += (what.empty() ? "" : ", ") + path + " = " + value;
  const YamlNode root = parse_yaml(base.text, name);
  std::vector<YamlReplacement> replacements;
  for (const auto& [path, value] : values) {
    // The value's own document names the key, so a path that leads nowhere says which one.
    const YamlNode node = parse_yaml(value, name + " (with_ " + path + ")");
    replacements.push_back({path, node});
  }
  try {
    return make_scene(root.replaced(replacements), base.file, base.directory);
  } catch (const ConfigError& e) {
    throw ConfigError(e.file(), e.field(), e.problem() + " [with_: " + what + "]");
  }
}

}  // namespace

void bind_scene(py::module_& m) {
  py::class_<PyScene>(m, "_Scene")
      .def(py::init([](const std::string& text, const std::string& file,
                       const std::string& directory) { return make_scene(text, file, directory); }),
           py::arg("text"), py::arg("file"), py::arg("directory"))
      .def_static(
          "load",
          [](const std::string& path) {
            auto text = simulator::read_scene_text(path);
            return make_scene(std::move(text), path,
                              std::filesystem::path(path).parent_path().string());
          },
          py::arg("path"))
      .def("_replaced", &replaced, py::arg("values"))
      .def_property_readonly("text", [](const PyScene& s) { return s.text; })
      .def_property_readonly("file",
                             [](const PyScene& s) {
                               return s.file.empty() ? py::object(py::none()) : py::str(s.file);
                             })
      .def_property_readonly("directory", [](const PyScene& s) { return s.directory; })
      .def_property_readonly("model_path", [](const PyScene& s) { return s.scene.model_path; })
      .def_property_readonly("title", [](const PyScene& s) { return s.scene.title; })
      .def_property_readonly("duration", [](const PyScene& s) { return s.scene.duration; })
      .def_property_readonly("time_scaling", [](const PyScene& s) { return s.scene.time_scaling; })
      .def_property_readonly("precision",
                             [](const PyScene& s) {
                               return std::string(simulator::precision_name(s.scene.precision));
                             })
      .def_property_readonly("effects",
                             [](const PyScene& s) {
                               std::vector<std::string> names;
                               for (const auto e : s.scene.effects)
                                 names.emplace_back(simulator::to_string(e));
                               return names;
                             })
      .def_property_readonly("activated_muscles", [](const PyScene& s) {
        std::vector<std::string> names;
        for (const auto& a : s.scene.activations) names.push_back(a.muscle);
        return names;
      });
}

}  // namespace sinew::python
