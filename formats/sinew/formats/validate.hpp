#pragma once
// The one validator of format v1. It checks a Model in memory; the reader runs it after loading a
// file and the writer before writing one, so no invalid model ever reaches or leaves a file.
//
// Every failure throws FormatError(file, dataset, problem).at(index), where dataset is the path
// the offending value has in the file (docs/model-format.md), e.g.
//   "face.h5: /element_materials/fraction[17]: fraction -0.1 outside [0, 1]"
// For data stored concatenated over muscles or surfaces (CSR), the index is the row in the
// concatenated dataset and the problem names the muscle or surface.
#include <string>

#include "sinew/formats/model.hpp"

namespace sinew::formats {

// Tolerances of the checks (docs/model-format.md, "Validation").
inline constexpr double kFractionSumTolerance = 1e-6;  // Σ fractions per element ≤ 1 + this
inline constexpr double kUnitLengthTolerance = 1e-6;   // | |fibre| − 1 | ≤ this
inline constexpr double kEmbeddingTolerance = 1e-9;    // ξ, η, ζ ∈ [−1 − this, 1 + this]
inline constexpr double kModulusRelativeTolerance = 1e-9;  // μ, κ versus E, ν

// Throws FormatError on the first violated invariant; `file` names the file in the message
// (the file being read or written, or a label such as "<memory>").
void validate_model(const Model& model, const std::string& file);

// True when `name` can be a named set's name: non-empty, no '/', not "." or "..", printable ASCII.
bool is_valid_set_name(const std::string& name);

}  // namespace sinew::formats
