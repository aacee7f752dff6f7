// sinew-inspect MODEL [--json] [--element N] [--node N]: validates a model file and prints its
// summary (text or JSON), or everything about one element or node (describe.hpp).
// Exit status 0 for a valid file, 1 (with the error on stderr) for an invalid or unreadable one.
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/formats/describe.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/summary.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Validate a sinew model file (HDF5, format v1) and print its summary.",
               "sinew-inspect"};
  std::string path;
  bool json = false;
  std::vector<sinew::formats::Index> elements, nodes;
  app.add_option("MODEL", path, "model file (.h5)")->required();
  auto* json_flag = app.add_flag("--json", json, "print the summary as one JSON document");
  app.add_option("--element", elements,
                 "print everything about element N instead of the summary (repeatable)")
      ->excludes(json_flag);
  app.add_option("--node", nodes,
                 "print everything about node N instead of the summary (repeatable)")
      ->excludes(json_flag);
  app.set_version_flag("--version", std::string("sinew-inspect ") + sinew::kVersion);
  CLI11_PARSE(app, argc, argv);

  return sinew::tool::run("sinew-inspect", [&] {
    const auto model = sinew::formats::read_model(path);
    if (!elements.empty() || !nodes.empty()) {
      std::string text;
      for (auto e : elements) text += sinew::formats::describe_element(model, e, path);
      for (auto n : nodes) text += sinew::formats::describe_node(model, n, path);
      std::fputs(text.c_str(), stdout);
      return sinew::tool::kExitOk;
    }
    const auto summary = sinew::formats::summarize(model);
    const std::string text =
        json ? sinew::formats::summary_json(summary) + "\n"
             : "file: " + path + " (valid)\n" + sinew::formats::summary_text(summary);
    std::fputs(text.c_str(), stdout);
    return sinew::tool::kExitOk;
  });
}
