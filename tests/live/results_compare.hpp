#pragma once
// Frames of a results file by engine step, read bit for bit (HDF5 C API), for comparing a live
// recording with its reproduction by sinew-simulate.
#include <hdf5.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace sinew::live::testing {

inline std::vector<double> read_doubles(const std::string& file, const std::string& name) {
  std::vector<double> v;
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return v;
  // A dataset the file lacks (e.g. /frames/J without the field J) reads as empty, quietly.
  const hid_t ds =
      H5Lexists(f, name.c_str(), H5P_DEFAULT) > 0 ? H5Dopen2(f, name.c_str(), H5P_DEFAULT) : -1;
  if (ds >= 0) {
    const hid_t sp = H5Dget_space(ds);
    v.resize(std::size_t(H5Sget_simple_extent_npoints(sp)));
    H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(sp);
    H5Dclose(ds);
  }
  H5Fclose(f);
  return v;
}

// step -> the frame's values of dataset `name` (e.g. "/frames/displacement").
inline std::map<std::int64_t, std::vector<double>> frames_by_step(const std::string& file,
                                                                  const std::string& name) {
  const auto steps = read_doubles(file, "/frames/step");
  const auto all = read_doubles(file, name);
  std::map<std::int64_t, std::vector<double>> out;
  if (steps.empty() || all.size() % steps.size() != 0) return out;
  const std::size_t width = all.size() / steps.size();
  for (std::size_t f = 0; f < steps.size(); ++f)
    out[std::int64_t(steps[f])] = std::vector<double>(
        all.begin() + std::ptrdiff_t(f * width), all.begin() + std::ptrdiff_t((f + 1) * width));
  return out;
}

}  // namespace sinew::live::testing
