#pragma once
// Checkpoints: the engine's complete State (state.hpp) plus a digest of what produced it, in HDF5.
// A run restarted from a checkpoint (sinew-simulate --restart FILE) continues bit-identically to
// the uninterrupted run; the digest makes sure it is the same scene, model and precision.
//
// Layout (N nodes, B sliding bindings), docs/results-format.md "Checkpoint":
//   attributes: format = "sinew-checkpoint", format_version = 1, digest (hex), scene_file,
//               model_file, step (I64), time (F64, s simulated), dt (F64, s), external_work (F64,
//               J), energy_reference (F64, J)
//   /u                 F64 N × 3, m, u(n)
//   /u_prev            F64 N × 3, m, u(n−1)
//   /sliding_triangle  I32 B
#include <string>

#include "sinew/simulator/engine/state.hpp"

namespace sinew::simulator {

inline constexpr const char* kCheckpointFormatName = "sinew-checkpoint";
inline constexpr int kCheckpointFormatVersion = 1;

struct Checkpoint {
  State state;
  std::string digest;      // run_digest() of the run that wrote it
  std::string scene_file;  // informational
  std::string model_file;  // informational
};

// SHA-256 (hex) over the scene file's bytes, the model file's bytes and the precision: a restart
// is refused when any of them differs.
std::string run_digest(const std::string& scene_text, const std::string& model_path,
                       const std::string& precision);
// The same digest from the model file's SHA-256 (hex) already computed (ModelCache).
std::string run_digest_from_hash(const std::string& scene_text, const std::string& model_sha256,
                                 const std::string& precision);

// Writes atomically (temporary file + rename). Throws IoError.
void write_checkpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws IoError (cannot open) or FormatError (not a checkpoint, wrong shapes).
Checkpoint read_checkpoint(const std::string& path);

}  // namespace sinew::simulator
