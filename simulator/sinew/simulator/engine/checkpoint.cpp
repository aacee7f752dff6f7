#include "sinew/simulator/engine/checkpoint.hpp"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <type_traits>

#include <fmt/format.h>

#include "sinew/common/atomic_file.hpp"
#include "sinew/common/error.hpp"
#include "sinew/formats/file_kind.hpp"
#include "sinew/formats/hdf5_file.hpp"
#include "sinew/formats/sha256.hpp"

namespace sinew::simulator {

namespace h5 = formats::hdf5;

namespace {

// Adds values to a SHA-256 as their little-endian bytes, so that a checkpoint's digests do not
// depend on the byte order of the machine that reads or writes it.
template <typename T>
void update_le(formats::Sha256& h, const T* values, std::size_t count) {
  static_assert(std::is_trivially_copyable_v<T>);
  if constexpr (std::endian::native == std::endian::little || sizeof(T) == 1) {
    h.update(values, count * sizeof(T));
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      unsigned char b[sizeof(T)];
      std::memcpy(b, &values[i], sizeof(T));
      std::reverse(b, b + sizeof(T));
      h.update(b, sizeof(T));
    }
  }
}

template <typename T>
std::string dataset_sha256(const std::vector<T>& values) {
  formats::Sha256 h;
  update_le(h, values.data(), values.size());
  return h.hex_digest();
}

// Each piece by name and length first, so that no two different checkpoints hash the same bytes.
void update_named(formats::Sha256& h, std::string_view name, const void* data, std::size_t size) {
  const std::uint64_t lengths[2] = {name.size(), size};
  update_le(h, lengths, 2);
  h.update(name);
  h.update(data, size);
}
void update_named(formats::Sha256& h, std::string_view name, const std::string& value) {
  update_named(h, name, value.data(), value.size());
}
template <typename T>
void update_named(formats::Sha256& h, std::string_view name, T value) {
  static_assert(std::is_arithmetic_v<T>);
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if constexpr (std::endian::native != std::endian::little) std::reverse(b, b + sizeof(T));
  update_named(h, name, b, sizeof(T));
}

struct StateDigests {
  std::string u, u_prev, sliding_triangle;
};

// The root digest: every other root attribute and the datasets' digests (checkpoint.hpp).
std::string state_sha256(const Checkpoint& c, const StateDigests& d) {
  const auto& s = c.state;
  formats::Sha256 h;
  update_named(h, "format_version", std::int64_t{kCheckpointFormatVersion});
  update_named(h, "digest", c.digest);
  update_named(h, "scene_file", c.scene_file);
  update_named(h, "model_file", c.model_file);
  update_named(h, "step", std::int64_t{s.step});
  update_named(h, "time", s.time);
  update_named(h, "dt", s.dt);
  update_named(h, "external_work", s.external_work);
  update_named(h, "energy_reference", s.energy_reference);
  update_named(h, "/u", d.u);
  update_named(h, "/u_prev", d.u_prev);
  update_named(h, "/sliding_triangle", d.sliding_triangle);
  return h.hex_digest();
}

// FormatError naming `field` when the stored digest is not `actual`; `what` says what it covers.
void check_digest(const std::string& path, const std::string& field, const std::string& stored,
                  const std::string& actual, const char* what) {
  if (stored == actual) return;
  throw FormatError(path, field,
                    fmt::format("{} do not match their SHA-256 digest written with them (stored "
                                "{}, computed {}): the checkpoint is damaged; restart from an "
                                "intact copy or rerun the scene from the start",
                                what, stored, actual));
}

}  // namespace

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
  const auto& s = c.state;
  if (s.u.size() != s.u_prev.size() || s.u.size() % 3 != 0) {
    throw IoError(path, "/u", "state arrays u and u_prev differ in size");
  }
  const StateDigests d{dataset_sha256(s.u), dataset_sha256(s.u_prev),
                       dataset_sha256(s.sliding_triangle)};
  write_atomically(path, [&](const std::string& tmp) {
    auto f = h5::create_file(tmp, path);
    h5::set_attribute(f, "format", std::string(kCheckpointFormatName), tmp);
    h5::set_attribute(f, "format_version", std::int64_t{kCheckpointFormatVersion}, tmp);
    h5::set_attribute(f, "digest", c.digest, tmp);
    h5::set_attribute(f, "scene_file", c.scene_file, tmp);
    h5::set_attribute(f, "model_file", c.model_file, tmp);
    h5::set_attribute(f, "step", std::int64_t{s.step}, tmp);
    h5::set_attribute(f, "time", s.time, tmp);
    h5::set_attribute(f, "dt", s.dt, tmp);
    h5::set_attribute(f, "external_work", s.external_work, tmp);
    h5::set_attribute(f, "energy_reference", s.energy_reference, tmp);
    h5::set_attribute(f, "state_sha256", state_sha256(c, d), tmp);
    const hsize_t n = s.u.size() / 3;
    const auto dataset = [&](const char* name, const auto& values, std::vector<hsize_t> dims,
                             const std::string& digest) {
      h5::write(f, name, dims, values.data(), tmp);
      h5::set_attribute(h5::open_dataset(f, name, tmp), "sha256", digest, tmp);
    };
    dataset("/u", s.u, {n, 3}, d.u);
    dataset("/u_prev", s.u_prev, {n, 3}, d.u_prev);
    dataset("/sliding_triangle", s.sliding_triangle, {s.sliding_triangle.size()},
            d.sliding_triangle);
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
  if (version == 1) {
    // Format 1 had no digest of its state: a damaged one restarted silently (issue 33).
    throw FormatError(
        path, "format_version",
        fmt::format("checkpoint format 1 was written by an older sinew and carries no "
                    "digest of its state, so damage to it cannot be detected; this "
                    "build restarts from format {} only: rerun the scene from the "
                    "start, or finish it with the build that wrote the checkpoint",
                    kCheckpointFormatVersion));
  }
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

  // The data first, so that a flipped bit is reported against the dataset that holds it.
  const StateDigests d{dataset_sha256(s.u), dataset_sha256(s.u_prev),
                       dataset_sha256(s.sliding_triangle)};
  const auto stored = [&](const char* name) {
    return h5::string_attribute(h5::open_dataset(f, name, path), "sha256", path + ":" + name);
  };
  check_digest(path, "/u", stored("/u"), d.u, "the values of /u, the displacements u(n),");
  check_digest(path, "/u_prev", stored("/u_prev"), d.u_prev,
               "the values of /u_prev, the displacements u(n−1),");
  check_digest(path, "/sliding_triangle", stored("/sliding_triangle"), d.sliding_triangle,
               "the values of /sliding_triangle, the sliding nodes' last triangles,");
  check_digest(path, "state_sha256", h5::string_attribute(f, "state_sha256", path),
               state_sha256(c, d),
               "the root attributes (step, time, dt, external_work, energy_reference, digest, "
               "scene_file, model_file) and the datasets' sha256 attributes");
  return c;
}

}  // namespace sinew::simulator
