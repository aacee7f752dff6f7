// When frames and probe rows are written (simulator/output/output_schedule.hpp): event k on the first
// step at or after k · interval, and an interval too long for the int64 step range (1e308 s, as
// scripts/fuzz_inputs.py wrote into a scene) gives no events after the first instead of a hang.
#include "sinew/simulator/output/output_schedule.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <limits>

namespace sinew::simulator {
namespace {

constexpr auto kNever = std::numeric_limits<std::int64_t>::max();

TEST(OutputSchedule, EventsFallOnTheFirstStepAtOrAfterTheirTime) {
  EXPECT_EQ(event_step(0, 0.5e-3, 1.0, 1e-4), 0);
  EXPECT_EQ(event_step(1, 0.5e-3, 1.0, 1e-4), 5);
  EXPECT_EQ(event_step(3, 0.25e-3, 1.0, 1e-4), 8);  // 7.5 steps: the next one
  OutputSchedule frames(0.5e-3, 1.0, 1e-4, 12, false);
  EXPECT_EQ(frames.next_after(0), 5);
  EXPECT_EQ(frames.next_after(5), 10);
  EXPECT_EQ(frames.next_after(10), 12);  // the last step, always written
  EXPECT_EQ(frames.next_after(12), kNever);
}

// Without the bound, the cast of an infinite step gave INT64_MIN, every event looked already
// passed and next_after() counted k up for ever (sinew-simulate hung on `interval: 1e308`).
TEST(OutputSchedule, AnIntervalPastTheStepRangeHasNoFurtherEvents) {
  EXPECT_EQ(event_step(1, 1e308, 1.0, 1e-5), kNever);
  EXPECT_EQ(event_step(1, 1e300, 1e10, 1e-9), kNever);
  EXPECT_EQ(event_step(std::int64_t(1) << 40, 1.0, 1.0, 1e-9), kNever);
  OutputSchedule frames(1e308, 1.0, 1.2e-5, 160, false);
  EXPECT_EQ(frames.next_after(0), 160);
  EXPECT_EQ(frames.next_after(159), 160);
  EXPECT_EQ(frames.next_after(160), kNever);
}

// An interval of 1e-308 s: the jump to the events of a step stopped at k = 2^62 and next_after()
// counted k up for ever from there. Events at most a step apart fall on every step; checked
// against counting k up one at a time for intervals of a quarter, 0.7 and one step.
TEST(OutputSchedule, EventsAtMostAStepApartFallOnEveryStep) {
  OutputSchedule tiny(1e-308, 1.0, 1.2e-5, 160, false);
  EXPECT_EQ(tiny.next_after(0), 1);
  EXPECT_EQ(tiny.next_after(41), 42);
  EXPECT_EQ(tiny.next_after(159), 160);
  EXPECT_EQ(tiny.next_after(160), kNever);
  for (const double share : {0.25, 0.7, 1.0}) {
    const double dt = 1.7e-5, interval = share * dt / 2.0;  // time_scaling 2
    OutputSchedule schedule(interval, 2.0, dt, 300, false);
    std::int64_t k = 0;
    for (std::int64_t step = 0; step < 300; ++step) {
      while (event_step(k, interval, 2.0, dt) <= step) ++k;
      EXPECT_EQ(schedule.next_after(step),
                std::min<std::int64_t>(event_step(k, interval, 2.0, dt), 300))
          << "share " << share << ", step " << step;
    }
  }
}

}  // namespace
}  // namespace sinew::simulator
