#pragma once
// Command-line options shared by the post-processing tools (sinew-render, sinew-export,
// sinew-wrinkles).
#include <CLI/CLI.hpp>

#include <string>

namespace sinew::postprocess {

// The results file (positional, must exist) and --surface, both as read_surface takes them.
inline void add_results_options(CLI::App& app, std::string& results, std::string& surface) {
  app.add_option("results", results, "results.h5 written by sinew-simulate")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--surface", surface,
                 "Visual surface (default: the only one; \"volume\": the volume's boundary, also "
                 "used when the file has no surface)");
}

}  // namespace sinew::postprocess
