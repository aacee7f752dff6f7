#pragma once
// Where the results frames land in an animation tool's timeline (Blender, three.js), shared by the
// glTF and PC2 exports so both put results frame k on the same Blender frame.
//
// Two modes:
//   one frame per frame (time_scale = 0, the default): results frame k is animation frame k, at
//     time k / fps s; the animation plays the scene slowed down by (output rate) / fps.
//   time scale S > 0: results frame k is animation frame n_k = round((t_k − t_0) S fps), at time
//     n_k / fps: scene time × S, snapped to whole frames so no key falls between two frames.
//
// The default frame rate (fps = 0 in FrameTimingOptions) is 24 or 30 frames per second, whichever
// makes the mode's factor x closer to a whole number n ≥ 1 relative to it (|x − n| / n), 24
// (Blender's default) on a tie:
//   one frame per frame: the slow-motion factor r / fps, r = 1 / Δt the output rate (Hz), Δt the
//     median interval between results frames (s); e.g. 200 Hz → 24 fps (8.33× is 4.2 % off 8,
//     6.67× 4.8 % off 7), 60 Hz → 30 fps (2×), 100 Hz → 24 fps (4.17×);
//   time scale S: the animation frames per results frame Δt S fps; e.g. Δt S = 0.1 s → 30 fps
//     (3 frames; 24 fps would give 2.4). When the rate so chosen puts two results frames on one
//     frame and the other does not, the other (Δt S = 0.04 s: 30 fps, 1.2 frames apart, not 0.96).
//
// Key times are the largest float t with t × fps ≤ n (in double): Blender's importer puts a key at
// frame t × fps and holds a STEP key from that frame on, so a key a rounding error after its frame
// would show the previous results frame there.
#include <cstdint>
#include <vector>

namespace sinew::postprocess {

struct FrameTimingOptions {
  double fps = 0.0;         // frames per second; 0: the default above
  double time_scale = 0.0;  // 0: one results frame per frame; > 0: animation time = scene time × S
};

struct FrameTiming {
  double fps = 24.0;                // frames per second of the timeline
  std::vector<std::int64_t> frame;  // F animation frames, frame[0] = 0, strictly increasing
  std::vector<float> time;          // F key times, s: time[k] = key_time(frame[k], fps)
};

// The default frame rate for `times` (F ≥ 1 scene times, s, increasing) and a time scale (0: one
// results frame per frame). F = 1 gives 24.
double default_fps(const std::vector<double>& times, double time_scale = 0.0);

// The largest float t ≥ 0 with t × fps ≤ n (n ≥ 0 frames).
float key_time(std::int64_t frame, double fps);

// The timing of `times` (F ≥ 1 scene times, s, strictly increasing). Throws ConfigError (field
// "--fps" or "--time-scale") on a non-positive or non-finite fps or a negative time scale, and
// when a time scale puts two results frames on the same animation frame (naming both).
FrameTiming frame_timing(const std::vector<double>& times, const FrameTimingOptions& options = {});

}  // namespace sinew::postprocess
