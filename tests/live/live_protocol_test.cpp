// The control messages (protocol.hpp) and the exactness of reproduced activation curves
// (steering_log.hpp): every step's activation of the reproduced curve equals the live value bit
// for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <string>

#include "sinew/live/protocol.hpp"
#include "sinew/live/steering_log.hpp"

namespace sinew::live {
namespace {

std::string refusal(const std::string& text) {
  try {
    parse_command(text);
  } catch (const ProtocolError& e) {
    return e.message;
  }
  return "";
}

TEST(LiveProtocol, ParsesEveryMessageType) {
  auto c = parse_command(R"({"type": "activation", "muscle": "flexor", "value": 0.25, "id": 7})");
  EXPECT_EQ(c.kind, Command::Kind::activation);
  EXPECT_EQ(c.muscle, "flexor");
  EXPECT_EQ(*c.value, 0.25);
  EXPECT_EQ(c.id, 7u);
  c = parse_command(R"({"type": "activation", "muscle": "flexor", "value": null})");
  EXPECT_FALSE(c.value.has_value());
  EXPECT_EQ(parse_command(R"({"type": "step", "count": 12})").count, 12);
  c = parse_command(
      R"({"type": "drag", "point": [0, 0.001, 2], "force": [0, 0, -0.5], "radius": 0.003})");
  EXPECT_EQ(c.kind, Command::Kind::drag);
  EXPECT_EQ(c.force[2], -0.5);
  EXPECT_EQ(parse_command(R"({"type": "field", "field": "jacobian"})").field, Field::jacobian);
  EXPECT_TRUE(parse_command(R"({"type": "record", "on": true})").on);
  for (const char* t : {"pause", "resume", "reset", "release"})
    EXPECT_NO_THROW(parse_command(std::string(R"({"type": ")") + t + "\"}"));
}

TEST(LiveProtocol, RefusesBadMessagesWithAReason) {
  EXPECT_EQ(refusal("{not json"), "malformed JSON");
  EXPECT_EQ(refusal("[1, 2]"), "a message must be a JSON object");
  EXPECT_EQ(refusal(R"({"kind": "pause"})"), "missing 'type' (a string)");
  EXPECT_NE(refusal(R"({"type": "explode"})").find("unknown message type 'explode'"),
            std::string::npos);
  EXPECT_NE(
      refusal(R"({"type": "activation", "muscle": "m", "value": 1.5})").find("outside [0, 1]"),
      std::string::npos);
  EXPECT_NE(refusal(R"({"type": "activation", "muscle": "m", "value": -0.1})").find("outside"),
            std::string::npos);
  // JSON has no NaN; an overflowing literal reads as infinity and is refused as not finite.
  EXPECT_EQ(refusal(R"({"type": "activation", "muscle": "m", "value": NaN})"), "malformed JSON");
  EXPECT_FALSE(refusal(R"({"type": "activation", "muscle": "m", "value": 1e999})").empty());
  EXPECT_FALSE(
      refusal(R"({"type": "drag", "point": [0, 0, 1e999], "force": [0, 0, 0], "radius": 0.01})")
          .empty());
  EXPECT_NE(
      refusal(R"({"type": "drag", "point": [0, 0, 0], "force": [0, 0, 1000], "radius": 0.01})")
          .find("above the limit"),
      std::string::npos);
  EXPECT_NE(refusal(R"({"type": "drag", "point": [0, 0], "force": [0, 0, 0], "radius": 0.01})")
                .find("3 numbers"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"type": "drag", "point": [0, 0, 0], "force": [0, 0, 0], "radius": -1})")
                .find("radius"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"type": "step", "count": 0})").find("count"), std::string::npos);
  EXPECT_NE(refusal(R"({"type": "step", "count": 1.5})").find("count"), std::string::npos);
  EXPECT_NE(refusal(R"({"type": "pause", "extra": 1})").find("unknown key 'extra'"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"type": "pause", "id": -3})").find("'id'"), std::string::npos);
  EXPECT_NE(refusal(R"({"type": "field", "field": "colour"})").find("'field'"), std::string::npos);
  EXPECT_NE(refusal(std::string(5000, ' ')).find("too long"), std::string::npos);
}

TEST(LiveProtocol, FrameLayoutIsAsDocumented) {
  const std::vector<float> d{1, 2, 3, 4, 5, 6}, v{7, 8};
  const auto f = encode_frame(42, 0.5, Field::von_mises, 9, d, v);
  ASSERT_EQ(f.size(), kFrameHeaderBytes + 16 * 2);
  std::uint32_t h[4];
  double sd[2];
  std::memcpy(h, f.data(), 16);
  std::memcpy(sd, f.data() + 16, 16);
  EXPECT_EQ(h[0], kTagFrame);
  EXPECT_EQ(h[1], 2u);
  EXPECT_EQ(h[2], 1u);
  EXPECT_EQ(h[3], 9u);
  EXPECT_EQ(sd[0], 42.0);
  EXPECT_EQ(sd[1], 0.5);
  float last;
  std::memcpy(&last, f.data() + f.size() - 4, 4);
  EXPECT_EQ(last, 8.0f);
}

// The activation BackendCore gives at step n (its header's law, restated): the scene's clamped
// curve until the first change; each change ramps linearly over 0.03 s of steps from the value its
// step had to its target (or to the curve's value), then holds it.
double live_value(const simulator::Curve& c, const std::vector<ActivationChange>& changes,
                  std::int64_t n, double dt, double s) {
  const auto curve = [&](std::int64_t m) {
    return c.points.empty() ? 0.0 : std::clamp(c.at((double(m) * dt) / s), 0.0, 1.0);
  };
  const std::int64_t ramp = std::max<std::int64_t>(1, std::llround(0.03 / dt));
  bool scene = true;
  std::optional<double> target;
  double from = 0;
  std::int64_t start = 0;
  const auto at = [&](std::int64_t m) {
    if (scene) return curve(m);
    const double to = target ? *target : curve(m);
    if (m >= start + ramp) return to;
    return from + (to - from) * (double(m - start) / double(ramp));
  };
  for (const auto& ch : changes) {
    if (ch.step > n) break;
    const double f = at(ch.step);
    scene = false;
    target = ch.value;
    from = f;
    start = ch.step;
  }
  return at(n);
}

TEST(LiveReproduce, ActivationCurveGivesEveryStepsValueExactly) {
  const double dt = 2.2396612e-4, s = 1.0;
  // Ramp 0 → 0.3 over 0.05 s, hold, release from 0.4 s to 0.45 s (three sloped segments).
  const simulator::Curve scene{{{0.0, 0.0}, {0.05, 0.3}, {0.4, 0.3}, {0.45, 0.0}}};
  const std::vector<std::vector<ActivationChange>> cases = {
      {{100, 0, 0.8}},                          // inside the hold, never back
      {{100, 0, 0.8}, {150, 0, std::nullopt}},  // back to the curve in the hold
      {{50, 0, 0.7}, {120, 0, std::nullopt}},   // from the ramp, back in the hold
      {{10, 0, 0.7}, {30, 0, std::nullopt}},    // both inside the ramp
      {{0, 0, 1.0}, {1900, 0, std::nullopt}},   // from step 0, back during the release
      {{1500, 0, 0.1}, {1500, 0, 0.2}, {1800, 0, 0.9}, {1850, 0, std::nullopt}},
  };
  const std::int64_t end = 2100;
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto knots = reproduce_activation(scene, cases[k], dt, s, end);
    const simulator::Curve reproduced{knots};
    ASSERT_TRUE(reproduced.valid()) << "case " << k;
    for (std::int64_t n = 0; n <= end; ++n) {
      const double t = (double(n) * dt) / s;
      ASSERT_EQ(std::clamp(reproduced.at(t), 0.0, 1.0), live_value(scene, cases[k], n, dt, s))
          << "case " << k << ", step " << n;
    }
  }
}

}  // namespace
}  // namespace sinew::live
