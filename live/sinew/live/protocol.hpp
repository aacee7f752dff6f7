#pragma once
// The message protocol of sinew-live (docs/live.md, "Protocol"): JSON text messages for control,
// binary WebSocket messages for geometry and frames. Version 1.
//
// Binary messages, little-endian, 4-byte aligned:
//   mesh  (once per client, after "hello"): u32 tag 1, u32 V, u32 T, u32 0,
//         f32 rest positions V × 3 (m), u32 triangles T × 3 (vertex ids, counter-clockwise seen
//         from outside). 16 + 12 V + 12 T bytes.
//   frame: u32 tag 2, u32 V, u32 field (0 |u| m, 1 von Mises Pa, 2 J), u32 last command id applied,
//          f64 step, f64 scene time (s), f32 displacement V × 3 (m), f32 field V.
//          32 + 16 V bytes (kFrameHeaderBytes + 16 V).
// Control messages from the client: {"type": ..., "id": optional non-negative integer echoed in
// the frames that first reflect it}; parse_command validates them (types, finiteness, ranges).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sinew::live {

inline constexpr int kProtocolVersion = 1;
inline constexpr std::size_t kMaxMessageBytes = 4096;  // a longer control message is refused
inline constexpr std::uint32_t kTagMesh = 1, kTagFrame = 2;
inline constexpr std::size_t kFrameHeaderBytes = 32;
inline constexpr std::int64_t kMaxStepCount = 100000;  // "step" messages: 1 .. this
inline constexpr double kMaxDragForce = 100.0;         // N, the total force of a drag
inline constexpr double kMaxDragRadius = 1.0;          // m

enum class Field : std::uint32_t { displacement = 0, von_mises = 1, jacobian = 2 };
const char* field_name(Field f);

struct Command {
  enum class Kind {
    activation,
    pause,
    resume,
    step,
    reset,
    drag,
    release,
    record,
    field,
    seek,
    resume_from
  };
  Kind kind = Kind::pause;
  std::uint32_t id = 0;               // the client's id for it (0: none)
  std::string muscle;                 // activation
  std::optional<double> value;        // activation in [0, 1]; none: back to the curve
  std::int64_t count = 1;             // step
  std::array<double, 3> point{};      // drag: picked point, m (deformed position)
  std::array<double, 3> force{};      // drag: total force, N, spread evenly over the nodes
  double radius = 0;                  // drag: m
  bool on = false;                    // record
  Field field = Field::displacement;  // field
};

// Parses one control message. Throws ProtocolError with a message for the client.
Command parse_command(std::string_view text);

struct ProtocolError : std::exception {
  explicit ProtocolError(std::string m) : message(std::move(m)) {}
  const char* what() const noexcept override { return message.c_str(); }
  std::string message;
};

// {"type": "error", "message": ...} (and the command id when known).
std::string error_message(const std::string& message, std::uint32_t id = 0);

// The binary messages.
std::string encode_mesh(const std::vector<float>& rest,
                        const std::vector<std::uint32_t>& triangles);
std::string encode_frame(std::int64_t step, double time, Field field, std::uint32_t command_id,
                         const std::vector<float>& displacement, const std::vector<float>& values);

}  // namespace sinew::live
