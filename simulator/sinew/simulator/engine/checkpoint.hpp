#pragma once
// Checkpoints: the engine's complete State (state.hpp) plus a digest of what produced it, in HDF5.
// A run restarted from a checkpoint (sinew-simulate --restart FILE) continues bit-identically to
// the uninterrupted run; the run digest makes sure it is the same scene, model and precision, and
// the state digests that the state is the one written (no bit of it flipped on disk).
//
// Layout (N nodes, B sliding bindings), docs/results-format.md "checkpoint.h5":
//   attributes: format = "sinew-checkpoint", format_version = 2, digest (hex), scene_file,
//               model_file, step (I64), time (F64, s simulated), dt (F64, s), external_work (F64,
//               J), energy_reference (F64, J), state_sha256 (hex)
//   /u                 F64 N × 3, m, u(n)           attribute sha256 (hex)
//   /u_prev            F64 N × 3, m, u(n−1)         attribute sha256 (hex)
//   /sliding_triangle  I32 B                        attribute sha256 (hex)
// Each dataset's sha256 is the SHA-256 of its values as little-endian bytes (IEEE 754 binary64 for
// F64, two's complement for I32), row-major. state_sha256 is the SHA-256 of every other root
// attribute and the three dataset digests, in a fixed order (state_sha256() in checkpoint.cpp):
// a flipped bit anywhere in what a restart reads is refused, naming the dataset or the attributes.
// Format 1 (before the state digests) is refused with a message saying so.
#include <string>

#include "sinew/simulator/engine/state.hpp"

namespace sinew::simulator {

inline constexpr const char* kCheckpointFormatName = "sinew-checkpoint";
inline constexpr int kCheckpointFormatVersion = 2;

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

// Writes atomically (temporary file + rename), with the state digests. Throws IoError.
void write_checkpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws IoError (cannot open) or FormatError (not a checkpoint, an older format, wrong shapes, or
// data that does not match its digest: the error names the dataset, or `state_sha256` for the
// root attributes). Whether the state fits a run (Δt, node count, step against the planned steps,
// time against step · Δt) is BackendCore::check_state's part, at restore.
Checkpoint read_checkpoint(const std::string& path);

}  // namespace sinew::simulator
