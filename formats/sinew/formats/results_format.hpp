#pragma once
// The results file's identity (docs/results-format.md): the root attributes `format` and
// `format_version` that the simulator's writer stamps and every reader checks.
namespace sinew::formats {

inline constexpr const char* kResultsFormatName = "sinew-results";
inline constexpr int kResultsFormatVersion = 1;

}  // namespace sinew::formats
