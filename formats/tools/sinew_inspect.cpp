// sinew-inspect MODEL [--json]: validates a model file and prints its summary (text or JSON).
// Exit status 0 for a valid file, 1 (with the error on stderr) for an invalid or unreadable one.
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "sinew/common/tool.hpp"
#include "sinew/common/version.hpp"
#include "sinew/formats/model_file.hpp"
#include "sinew/formats/summary.hpp"

int main(int argc, char** argv) {
  CLI::App app{"Validate a sinew model file (HDF5, format v1) and print its summary.",
               "sinew-inspect"};
  std::string path;
  bool json = false;
  app.add_option("MODEL", path, "model file (.h5)")->required();
  app.add_flag("--json", json, "print the summary as one JSON document");
  app.set_version_flag("--version", std::string("sinew-inspect ") + sinew::kVersion);
  CLI11_PARSE(app, argc, argv);

  return sinew::tool::run("sinew-inspect", [&] {
    const auto model = sinew::formats::read_model(path);
    const auto summary = sinew::formats::summarize(model);
    const std::string text =
        json ? sinew::formats::summary_json(summary) + "\n"
             : "file: " + path + " (valid)\n" + sinew::formats::summary_text(summary);
    std::fputs(text.c_str(), stdout);
    return sinew::tool::kExitOk;
  });
}
