// sinew.run: what sinew-simulate does (runner.hpp's run_scene), from a Python scene. The scene is
// written into the output folder first, as scene.yaml with its model path made absolute (as
// sinew-sweep writes each run's), so the folder holds what reproduces it with the tool.
//
// Ctrl-C: Python keeps SIGINT, so the run works on another thread while this one waits with the
// GIL, checking Python's signals every 50 ms; on KeyboardInterrupt it asks the run to stop
// (request_interrupt), which then stops at a step boundary with a checkpoint (status
// "interrupted", as sinew-simulate's SIGINT), and re-raises KeyboardInterrupt.
#include <nlohmann/json.hpp>

#include <filesystem>

#include "bindings.hpp"
#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"
#include "sinew/simulator/run/runner.hpp"

namespace sinew::python {
namespace {

namespace fs = std::filesystem;

// The scene's text with its model path absolute (the folder it is written to is not the scene's).
std::string with_absolute_model(const PyScene& scene) {
  const std::string name = scene_name(scene);
  const auto absolute = fs::absolute(scene.scene.model_path).lexically_normal().string();
  const auto root = parse_yaml(scene.text, name);
  return root.replaced({{"model", parse_yaml(nlohmann::json(absolute).dump(), name)}});
}

}  // namespace

void bind_run(py::module_& m) {
  m.def(
      "_run",
      [](const PyScene& scene, const std::string& out, const std::string& device,
         const py::object& precision, int threads, bool progress, bool force,
         const std::string& restart, std::int64_t checkpoint_every, bool explain) {
        if (threads < 0) throw ConfigError("", "threads", "must be ≥ 0 (0: OpenMP's default)");
        if (checkpoint_every < 0) throw ConfigError("", "checkpoint_every", "must be ≥ 0");
        simulator::RunOptions o;
        o.output_dir = out;
        o.device = device;
        o.precision = precision_from(precision);
        o.threads = threads;
        o.quiet = !progress;
        o.force = force;
        o.restart = restart;
        o.checkpoint_every = checkpoint_every;
        o.explain = explain;
        const std::string text = with_absolute_model(scene);
        std::error_code ec;
        fs::create_directories(out, ec);
        if (ec) throw IoError(out, "", "cannot create the output folder: " + ec.message());
        o.scene_path = (fs::path(out) / "scene.yaml").string();
        write_text_atomically(o.scene_path, text);
        const auto result = run_watching_signals([o] { return simulator::run_scene(o); });
        return result.output_dir;
      },
      py::arg("scene"), py::arg("out"), py::arg("device"), py::arg("precision"), py::arg("threads"),
      py::arg("progress"), py::arg("force"), py::arg("restart"), py::arg("checkpoint_every"),
      py::arg("explain"));
}

}  // namespace sinew::python
