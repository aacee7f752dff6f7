#include "sinew/simulator/engine/checkpoint.hpp"

#include <cstdio>

#include <fmt/format.h>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/file_kind.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/sha256.hpp"

namespace sinew::simulator {

namespace h5 = formats::hdf5;

std::string run_digest(const std::string& scene_text, const std::string& model_path,
                       const std::string& precision) {
  return run_digest_from_hash(scene_text, formats::sha256_file(model_path), precision);
}

std::string run_digest_from_hash(const std::string& scene_text, const std::string& model_sha256,
                                 const std::string& precision) {
  formats::Sha256 h;
  h.update("scene\n");
  h.update(scene_text);
  h.update("\nmodel\n");
  h.update(model_sha256);
  h.update("\nprecision\n");
  h.update(precision);
  return h.hex_digest();
}

void write_checkpoint(const std::string& path, const Checkpoint& c) {
  write_atomically(path, [&](const std::string& tmp) {
    auto f = h5::create_file(tmp, path);
    h5::set_attribute(f, "format", std::string(kCheckpointFormatName), tmp);
    h5::set_attribute(f, "format_version", std::int64_t{kCheckpointFormatVersion}, tmp);
    h5::set_attribute(f, "digest", c.digest, tmp);
    h5::set_attribute(f, "scene_file", c.scene_file, tmp);
    h5::set_attribute(f, "model_file", c.model_file, tmp);
    const auto& s = c.state;
    h5::set_attribute(f, "step", std::int64_t{s.step}, tmp);
    h5::set_attribute(f, "time", s.time, tmp);
    h5::set_attribute(f, "dt", s.dt, tmp);
    h5::set_attribute(f, "external_work", s.external_work, tmp);
    h5::set_attribute(f, "energy_reference", s.energy_reference, tmp);
    if (s.u.size() != s.u_prev.size() || s.u.size() % 3 != 0) {
      throw IoError(path, "/u", "state arrays u and u_prev differ in size");
    }
    const hsize_t n = s.u.size() / 3;
    h5::write(f, "/u", {n, 3}, s.u.data(), tmp);
    h5::write(f, "/u_prev", {n, 3}, s.u_prev.data(), tmp);
    h5::write(f, "/sliding_triangle", {s.sliding_triangle.size()}, s.sliding_triangle.data(), tmp);
    h5::close_file(f, path);
  });
}

Checkpoint read_checkpoint(const std::string& path) {
  auto f = h5::open_file(path, false);
  if (!formats::has_format(f, path, kCheckpointFormatName)) {
    throw formats::wrong_kind(
        f, path, "a sinew checkpoint",
        "--restart takes the checkpoint.h5 of an interrupted run's output folder");
  }
  const auto version = h5::int_attribute(f, "format_version", path);
  if (version != kCheckpointFormatVersion) {
    throw FormatError(path, "format_version",
                      fmt::format("version {} is not supported (this build reads {})", version,
                                  kCheckpointFormatVersion));
  }
  Checkpoint c;
  c.digest = h5::string_attribute(f, "digest", path);
  c.scene_file = h5::string_attribute(f, "scene_file", path);
  c.model_file = h5::string_attribute(f, "model_file", path);
  auto& s = c.state;
  s.step = h5::int_attribute(f, "step", path);
  s.time = h5::double_attribute(f, "time", path);
  s.dt = h5::double_attribute(f, "dt", path);
  s.external_work = h5::double_attribute(f, "external_work", path);
  s.energy_reference = h5::double_attribute(f, "energy_reference", path);
  const auto shape = h5::shape(f, "/u", path);
  if (shape.size() != 2 || shape[1] != 3) throw FormatError(path, "/u", "expected shape N × 3");
  s.u = h5::read<double>(f, "/u", path);
  if (h5::shape(f, "/u_prev", path) != shape)  // a transposed 3 × N has the right count too
    throw FormatError(path, "/u_prev", "expected the shape of /u, N × 3");
  s.u_prev = h5::read<double>(f, "/u_prev", path, static_cast<std::int64_t>(s.u.size()));
  s.sliding_triangle = h5::read<std::int32_t>(f, "/sliding_triangle", path);
  return c;
}

}  // namespace sinew::simulator
