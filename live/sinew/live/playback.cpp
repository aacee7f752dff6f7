#include "sinew/live/playback.hpp"

#include <hdf5.h>

#include <filesystem>

#include <fmt/format.h>

#include "sinew/common/error.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/results_format.hpp"

namespace sinew::live {

namespace h5 = formats::hdf5;

RecordedRun::RecordedRun(std::string path) : path_(std::move(path)) {
  const auto f = h5::open_checked(path_);
  if (!h5::has_attribute(f, "format") ||
      h5::string_attribute(f, "format", path_) != formats::kResultsFormatName)
    throw FormatError(path_, "/", "not a sinew results file (attribute format)");
  times_ = h5::read<double>(f, "/frames/time", path_);
  const auto steps = h5::read<std::int64_t>(f, "/frames/step", path_);
  steps_.assign(steps.begin(),
                steps.begin() + std::ptrdiff_t(std::min(steps.size(), times_.size())));
  times_.resize(steps_.size());
  const auto shape = h5::shape(f, "/frames/displacement", path_);
  if (shape.size() != 3 || shape[2] != 3 || shape[0] < steps_.size())
    throw FormatError(path_, "/frames/displacement", "expected a frames × N × 3 dataset");
  nodes_ = std::size_t(shape[1]);
  if (steps_.empty()) throw FormatError(path_, "/frames/step", "the file has no frame");
  if (h5::has_attribute(f, "scene_file"))
    scene_attribute_ = h5::string_attribute(f, "scene_file", path_);
  for (const char* dataset : {"/frames/von_mises", "/frames/J"}) {
    if (!h5::exists(f, dataset)) continue;
    const auto field = h5::shape(f, dataset, path_);
    if (field.size() != 2 || field[0] < steps_.size())
      throw FormatError(path_, dataset, "expected a frames × elements dataset");
    element_fields_.emplace_back(dataset, std::size_t(field[1]));
  }
}

std::vector<double> RecordedRun::displacement(std::size_t k) const {
  return read_frame("/frames/displacement", k, nodes_ * 3);
}

std::size_t RecordedRun::element_field_width(const std::string& dataset) const {
  for (const auto& [name, width] : element_fields_)
    if (name == dataset) return width;
  return 0;
}

std::vector<double> RecordedRun::element_field(const std::string& dataset, std::size_t k) const {
  const auto width = element_field_width(dataset);
  if (width == 0) throw FormatError(path_, dataset, "the file has no such element field");
  return read_frame(dataset, k, width);
}

std::vector<double> RecordedRun::read_frame(const std::string& dataset, std::size_t k,
                                            std::size_t values) const {
  if (k >= steps_.size())
    throw FormatError(path_, dataset,
                      fmt::format("frame {} out of range (the file has {})", k, steps_.size()));
  const auto f = h5::open_checked(path_);
  const auto ds = h5::open_dataset(f, dataset, path_);
  std::vector<double> out(values);
  const h5::Handle file_space(H5Dget_space(ds), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(file_space);
  // One row of the first axis: (1, N, 3) for displacement, (1, E) for an element field.
  const hsize_t start[3] = {hsize_t(k), 0, 0};
  const hsize_t count[3] = {1, hsize_t(rank == 3 ? values / 3 : values), 3};
  const h5::Handle mem_space(H5Screate_simple(rank, count, nullptr), H5Sclose);
  if (rank < 2 || rank > 3 ||
      H5Sselect_hyperslab(file_space, H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
      H5Dread(ds, H5T_NATIVE_DOUBLE, mem_space, file_space, H5P_DEFAULT, out.data()) < 0)
    throw FormatError(path_, dataset, fmt::format("cannot read frame {}{}", k, h5::error_detail()));
  return out;
}

std::string RecordedRun::scene() const {
  const auto beside = std::filesystem::path(path_).parent_path() / "scene.yaml";
  if (std::filesystem::exists(beside)) return beside.string();
  if (scene_attribute_.empty())
    throw FormatError(path_, "/", "the file names no scene (attribute scene_file); give one");
  return scene_attribute_;
}

}  // namespace sinew::live
