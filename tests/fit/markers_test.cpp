// The marker CSV of sinew-fit (fit/sinew/fit/markers.hpp, docs/fit.md): a good file reads back
// exactly; each kind of bad input is a FormatError naming the file, the line and the value.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sinew/common/error.hpp"
#include "sinew/fit/markers.hpp"

namespace sinew::fit {
namespace {

const std::string kGood =
    "# two markers, mm\n"
    "time,chin.x,chin.y,chin.z,brow.x,brow.y,brow.z\n"
    "0,0,-101.4,66.3,25.6,31.8,87.6\n"
    "\n"
    "0.005, 0.1 ,-101.5,66.2,,,\n"
    "0.01,0.2,-101.6,66.1,25.7,31.9,87.5\n";

TEST(Markers, ReadsNamesTimesPositionsAndGaps) {
  const Markers m = parse_markers(kGood, "m.csv");
  ASSERT_EQ(m.names, (std::vector<std::string>{"chin", "brow"}));
  ASSERT_EQ(m.frame_count(), 3u);
  EXPECT_EQ(m.header_line, 2);
  EXPECT_EQ(m.lines, (std::vector<int>{3, 5, 6}));
  EXPECT_DOUBLE_EQ(m.times[1], 0.005);
  EXPECT_DOUBLE_EQ(m.positions[1][0][0], 0.1);
  EXPECT_FALSE(m.seen[1][1]);
  EXPECT_TRUE(m.seen[2][1]);
  EXPECT_EQ(m.seen_count(), 5u);
  // Written and read again: the same.
  const Markers again = parse_markers(markers_csv(m), "again.csv");
  EXPECT_EQ(again.positions, m.positions);
  EXPECT_EQ(again.seen, m.seen);
  EXPECT_EQ(again.times, m.times);
}

// The message of parsing `text`, which must throw a FormatError.
std::string error_of(const std::string& text) {
  try {
    parse_markers(text, "markers.csv");
  } catch (const FormatError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no error for:\n" << text;
  return {};
}

TEST(Markers, NaNNamesTheFileLineColumnAndValue) {
  const auto e = error_of("time,chin.x,chin.y,chin.z\n0,1,2,3\n0.01,1,nan,3\n");
  EXPECT_NE(e.find("markers.csv"), std::string::npos) << e;
  EXPECT_NE(e.find("line 3"), std::string::npos) << e;
  EXPECT_NE(e.find("chin.y"), std::string::npos) << e;
  EXPECT_NE(e.find("'nan'"), std::string::npos) << e;
  EXPECT_NE(error_of("time,chin.x,chin.y,chin.z\n0,1,2,inf\n").find("'inf'"), std::string::npos);
  EXPECT_NE(error_of("time,chin.x,chin.y,chin.z\n0,1,2,3x\n").find("'3x'"), std::string::npos);
}

TEST(Markers, TimeGoingBackwardsNamesBothRows) {
  const auto e = error_of("time,chin.x,chin.y,chin.z\n0,1,2,3\n0.02,1,2,3\n0.01,1,2,3\n");
  EXPECT_NE(e.find("markers.csv: line 4, column 'time'"), std::string::npos) << e;
  EXPECT_NE(e.find("0.01"), std::string::npos) << e;
  EXPECT_NE(e.find("line 3"), std::string::npos) << e;
  // A repeated time too, and a negative one.
  EXPECT_NE(error_of("time,a.x,a.y,a.z\n0,1,2,3\n0,1,2,3\n").find("line 3"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.y,a.z\n-0.1,1,2,3\n").find("before the scene's start"),
            std::string::npos);
}

TEST(Markers, MalformedHeadersAndRowsAreNamed) {
  EXPECT_NE(error_of("t,a.x,a.y,a.z\n").find("'time'"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.y\n").find("three per marker"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.z,a.y\n").find("expected column 'a.y'"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.y,a.z,a.x,a.y,a.z\n").find("appears twice"), std::string::npos);
  EXPECT_NE(error_of("time,a b.x,a b.y,a b.z\n").find("letters, digits"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.y,a.z\n0,1,2\n").find("line 2: 3 cells"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.y,a.z\n0,1,,3\n").find("1 of its 3 cells empty"),
            std::string::npos);
  EXPECT_NE(error_of("# nothing\n").find("no header"), std::string::npos);
  EXPECT_NE(error_of("time,a.x,a.y,a.z\n").find("no frames"), std::string::npos);
}

TEST(Markers, AMissingFileIsAnIoErrorNamingIt) {
  try {
    read_markers("/nonexistent/markers.csv");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/markers.csv"), std::string::npos);
  }
}

}  // namespace
}  // namespace sinew::fit
