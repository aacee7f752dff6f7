#pragma once
// Reading and writing model files: HDF5, format version 1, laid out dataset by dataset as
// docs/model-format.md describes. Both directions run validate_model(), so a file written here
// always reads back, and a file read here satisfies every invariant of model.hpp.
#include <string>

#include "sinew/formats/model.hpp"

namespace sinew::formats {

// Validates `model` (FormatError naming `path` on failure), then writes it to `path`. The data go
// to "<path>.tmp-<pid>" first, which is renamed to `path` only once complete and closed, so a crash
// never leaves a half-written file under the final name. The output is deterministic: the same
// model written twice gives byte-identical files (no object time stamps). Throws IoError when the
// file cannot be created, written or renamed.
void write_model(const Model& model, const std::string& path);

// Reads and validates a model file. Throws IoError when the file cannot be opened at all, and
// FormatError (file, dataset, index, problem) for anything else: not HDF5, truncated, wrong format
// name or version, a missing dataset, a wrong dtype or shape, and every validate_model() check.
// HDF5's own error printing is switched off; its messages end up in the exception text.
Model read_model(const std::string& path);

// The current time as ISO 8601 UTC, e.g. "2026-11-21T06:49:00Z", for Provenance::created.
std::string current_utc_iso8601();

}  // namespace sinew::formats
