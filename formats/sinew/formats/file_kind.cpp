#include "sinew/formats/file_kind.hpp"

#include <fmt/format.h>

#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/model.hpp"
#include "sinew/formats/results_format.hpp"

namespace sinew::formats {

namespace {

// The format attribute, or "" when it is missing or not a readable string.
std::string format_of(hid_t file, const std::string& path) {
  try {
    if (!hdf5::has_attribute(file, "format")) return {};
    return hdf5::string_attribute(file, "format", path);
  } catch (const Error&) {
    return {};  // a numeric or damaged attribute: no sinew format
  }
}

}  // namespace

std::string file_kind(hid_t file, const std::string& path) {
  const std::string format = format_of(file, path);
  if (format == kModelFormatName) return "a sinew model file";
  if (format == kResultsFormatName) return "a sinew results file";
  // The checkpoint's name is simulator/engine/checkpoint.hpp's kCheckpointFormatName.
  if (format == "sinew-checkpoint") return "a sinew checkpoint";
  if (format.empty()) return "an HDF5 file without a sinew format attribute";
  return fmt::format("an HDF5 file with format '{}'", format);
}

bool has_format(hid_t file, const std::string& path, const std::string& format_name) {
  return format_of(file, path) == format_name;
}

FormatError wrong_kind(hid_t file, const std::string& path, const std::string& expected,
                       const std::string& hint) {
  return FormatError(path, "format",
                     fmt::format("this is {}, not {}; {}", file_kind(file, path), expected, hint));
}

}  // namespace sinew::formats
