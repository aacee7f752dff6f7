// The shared YAML reader (common/yaml_reader.hpp): key paths, lines, conversions and the errors
// that name the file, the key and the line.
#include "sinew/common/yaml_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/common/names.hpp"

namespace sinew {
namespace {

// Runs `read` and returns the ConfigError it throws; fails the test when it throws none.
ConfigError config_error(const std::function<void()>& read) {
  try {
    read();
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "expected a ConfigError";
  return ConfigError("", "", "");
}

const char* kDoc =
    "name: box\n"          // line 1
    "size: 0.5\n"          // line 2
    "count: 3\n"           // line 3
    "flag: true\n"         // line 4
    "origin: [1, 2, 3]\n"  // line 5
    "empty:\n"             // line 6
    "inner:\n"             // line 7
    "  depth: -2\n"        // line 8
    "  colour: red\n"      // line 9
    "items:\n"             // line 10
    "  - {a: 1}\n"         // line 11
    "  - {a: x}\n";        // line 12

TEST(YamlReader, ReadsScalarsListsAndMaps) {
  const YamlNode root = parse_yaml(kDoc, "doc.yaml");
  EXPECT_TRUE(root.is_map());
  EXPECT_EQ(root.file(), "doc.yaml");
  EXPECT_EQ(root.path(), "");
  EXPECT_EQ(root.child("name").text(), "box");
  EXPECT_DOUBLE_EQ(root.child("size").positive(), 0.5);
  EXPECT_EQ(root.child("count").integer(), 3);
  EXPECT_TRUE(root.child("flag").boolean());
  EXPECT_EQ(root.child("origin").vec3(), (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(root.child("items").size(), 2u);
  EXPECT_EQ(root.child("items").item(1).child("a").path(), "items[1].a");
  EXPECT_EQ(root.child("inner").child("depth").path(), "inner.depth");
  EXPECT_EQ(root.child("inner").child("depth").line(), 8);
  EXPECT_EQ(root.keys(), (std::vector<std::string>{"name", "size", "count", "flag", "origin",
                                                   "empty", "inner", "items"}));
}

TEST(YamlReader, AbsentAndEmptyKeys) {
  const YamlNode root = parse_yaml(kDoc, "doc.yaml");
  EXPECT_FALSE(root.has("missing"));
  EXPECT_FALSE(root.has("empty"));  // `empty:` has no value: the same as leaving it out
  EXPECT_TRUE(root.has("inner"));
  const YamlNode missing = root.child("missing");
  EXPECT_FALSE(missing.defined());
  EXPECT_FALSE(missing.line().has_value());
  EXPECT_EQ(missing.path(), "missing");
  // Lookups below an absent key or in a scalar stay absent rather than failing.
  EXPECT_FALSE(missing.child("deeper").item(2).defined());
  EXPECT_FALSE(root.child("name").child("x").defined());
  EXPECT_FALSE(root.child("items").item(7).defined());
}

TEST(YamlReader, ItemsOfAList) {
  const YamlNode root = parse_yaml(kDoc, "doc.yaml");
  const auto items = root.child("items").items();
  ASSERT_EQ(items.size(), 2u);
  EXPECT_EQ(items[1].path(), "items[1]");
  EXPECT_EQ(items[1].line(), 12);
  EXPECT_TRUE(root.child("missing").items().empty());  // an absent list has no items
  const auto e = config_error([&] { root.child("inner").items(); });
  EXPECT_STREQ(e.what(), "doc.yaml: inner: expected a list (line 8)");
}

TEST(YamlReader, ErrorsNameFileKeyAndLine) {
  const YamlNode root = parse_yaml(kDoc, "doc.yaml");
  const auto e = config_error([&] { root.child("inner").child("depth").positive(); });
  EXPECT_EQ(e.file(), "doc.yaml");
  EXPECT_EQ(e.field(), "inner.depth");
  EXPECT_STREQ(e.what(), "doc.yaml: inner.depth: must be > 0, got -2 (line 8)");

  const auto item = config_error([&] { root.child("items").item(1).child("a").number(); });
  EXPECT_STREQ(item.what(), "doc.yaml: items[1].a: expected a number, got 'x' (line 12)");

  // An absent key has no line.
  const auto absent = config_error([&] { root.child("missing").number(); });
  EXPECT_STREQ(absent.what(), "doc.yaml: missing: expected a number");
}

// Issue 33: yaml-cpp converts a quoted '0.001' as it does 0.001, and YAML::Load reads the first of
// several documents and drops the rest; both passed without a word.
TEST(YamlReader, AQuotedNumberIsRefusedAndTheTextStaysText) {
  const YamlNode root =
      parse_yaml("dt: '0.001'\nsteps: \"3\"\nflag: 'true'\nname: '0.5'\n", "q.yaml");
  EXPECT_STREQ(config_error([&] { root.child("dt").number(); }).what(),
               "q.yaml: dt: expected a number, got the quoted string '0.001' (write it without "
               "quotes) (line 1)");
  EXPECT_NE(std::string(config_error([&] { root.child("steps").integer(); }).what())
                .find("got the quoted string '3'"),
            std::string::npos);
  EXPECT_NE(std::string(config_error([&] { root.child("flag").boolean(); }).what())
                .find("got the quoted string 'true'"),
            std::string::npos);
  EXPECT_EQ(root.child("name").text(), "0.5");
  // Unquoted, the same values are numbers.
  EXPECT_DOUBLE_EQ(parse_yaml("dt: 0.001\n", "u.yaml").child("dt").number(), 0.001);
}

TEST(YamlReader, ASecondDocumentIsRefused) {
  const auto e = config_error([] { parse_yaml("a: 1\n---\nb: 2\n", "two.yaml"); });
  EXPECT_STREQ(e.what(), "two.yaml: a second YAML document starts at line 2; give one document");
  // One document, with or without its `---`, and an empty file, are read as before.
  EXPECT_DOUBLE_EQ(parse_yaml("---\na: 1\n", "one.yaml").child("a").number(), 1.0);
  EXPECT_FALSE(parse_yaml("", "empty.yaml").has("a"));
  // A comment before the first `---` is no document; `---` inside a line is no marker.
  EXPECT_DOUBLE_EQ(parse_yaml("# c\n---\na: 1 # ---\nb: '---'\n", "c.yaml").child("a").number(),
                   1.0);
}

// yaml-cpp passes any byte on; a sweep title with invalid UTF-8 then made sinew-sweep end in an
// untyped "[json.exception.type_error.316] invalid UTF-8 byte" naming no file (fuzz_inputs.py).
TEST(YamlReader, TextThatIsNotUtf8IsRejectedWithItsLine) {
  EXPECT_STREQ(config_error([] { parse_yaml("version: 1\ntitle: ab\x9c\n", "s.yaml"); }).what(),
               "s.yaml: not UTF-8 text: byte 0x9C (line 2, column 10)");
  EXPECT_NE(std::string(config_error([] { parse_yaml("t: \xc3\x28\n", "s.yaml"); }).what())
                .find("byte 0xC3 (line 1, column 4)"),
            std::string::npos);
  // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8 either.
  for (const char* bad : {"t: \xc0\xaf", "t: \xed\xa0\x80", "t: \xf4\x90\x80\x80", "t: \xe2\x82"})
    config_error([&] { parse_yaml(bad, "s.yaml"); });
  // Multi-byte characters count as one column, and valid UTF-8 of every length passes.
  EXPECT_EQ(parse_yaml("t: \"\xc3\xa9\xe2\x80\xae\xf0\x9f\x98\x80\"\n", "s.yaml").child("t").text(),
            "\xc3\xa9\xe2\x80\xae\xf0\x9f\x98\x80");
  EXPECT_NE(std::string(config_error([] { parse_yaml("t: \xc3\xa9\xff", "s.yaml"); }).what())
                .find("(line 1, column 5)"),
            std::string::npos);
}

TEST(YamlReader, UnknownKeysAreRejectedAtTheKey) {
  const YamlNode root = parse_yaml(kDoc, "doc.yaml");
  const auto e = config_error([&] { root.child("inner").allow_keys({"depth", "width"}); });
  EXPECT_EQ(e.field(), "inner.colour");
  EXPECT_STREQ(
      e.what(),
      "doc.yaml: inner.colour: unknown key 'colour' (allowed here: depth, width) (line 9)");
  EXPECT_NO_THROW(root.child("inner").allow_keys({"colour", "depth"}));
  // Only maps have keys.
  EXPECT_NE(std::string(config_error([&] { root.child("origin").allow_keys({"x"}); }).what())
                .find("origin: expected a mapping of keys"),
            std::string::npos);
}

TEST(YamlReader, KeyGivenTwiceIsAnError) {
  const YamlNode root = parse_yaml("a: 1\nb:\n  c: 1\n  c: 2\n", "twice.yaml");
  const auto e = config_error([&] { root.child("b").keys(); });
  EXPECT_EQ(e.field(), "b.c");
  EXPECT_NE(std::string(e.what()).find("key 'c' given twice (line 4)"), std::string::npos)
      << e.what();
}

TEST(YamlReader, RequiredKeys) {
  const YamlNode root = parse_yaml(kDoc, "doc.yaml");
  EXPECT_EQ(root.require("inner").child("depth").integer(), -2);
  const auto e = config_error([&] { root.child("inner").require("width"); });
  EXPECT_EQ(e.field(), "inner");  // the map that lacks the key
  EXPECT_STREQ(e.what(), "doc.yaml: inner: missing key 'width' (line 8)");
  // An empty value is missing too.
  EXPECT_NE(
      std::string(config_error([&] { root.require("empty"); }).what()).find("missing key 'empty'"),
      std::string::npos);
}

TEST(YamlReader, TypeConversionFailures) {
  const YamlNode root = parse_yaml(
      "n: ten\nf: .nan\ni: 1.5\nb: maybe\nv: [1, 2]\nw: [1, a, 3]\nl: {x: 1}\nz: 0\ns: [a]\n",
      "types.yaml");
  // Each read and the message it must give.
  const std::vector<std::pair<std::function<void()>, std::string>> cases{
      {[&] { root.child("n").number(); }, "n: expected a number, got 'ten' (line 1)"},
      {[&] { root.child("f").number(); }, "f: expected a finite number, got '.nan' (line 2)"},
      {[&] { root.child("i").integer(); }, "i: expected an integer, got '1.5' (line 3)"},
      {[&] { root.child("b").boolean(); }, "b: expected true or false, got 'maybe' (line 4)"},
      {[&] { root.child("v").vec3(); }, "v: expected a list of 3 numbers [x, y, z] (line 5)"},
      {[&] { root.child("w").vec3(); }, "w[1]: expected a number, got 'a' (line 6)"},
      {[&] { root.child("l").number(); }, "l: expected a number (line 7)"},
      {[&] { root.child("l").text(); }, "l: expected a text value (line 7)"},
      {[&] { root.child("z").positive(); }, "z: must be > 0, got 0 (line 8)"},
      {[&] { root.child("s").expect_map(); }, "s: expected a mapping of keys (line 9)"},
      {[&] { root.child("l").expect_sequence(); }, "l: expected a list (line 7)"}};
  for (const auto& [read, message] : cases) {
    EXPECT_EQ(std::string(config_error(read).what()), "types.yaml: " + message);
  }
  EXPECT_DOUBLE_EQ(root.child("z").non_negative(), 0.0);
}

// Numbers are read without a locale (std::from_chars; yaml_reader.cpp says why): YAML 1.2's core
// schema, the forms yaml-cpp's stream read took, and nothing more.
TEST(YamlReader, NumbersInEveryFormAndNothingElse) {
  const YamlNode root = parse_yaml(
      "a: +5\nb: -.5\nc: 5.\nd: 1.0e5\ne: 2E-3\nf: 7\ng: -0.0\n"
      "i: 0x1F\nj: 0o17\nk: -9223372036854775808\nl: 9223372036854775807\nm: 010\n"
      "bad_inf: inf\nbad_nan: nan\nbad_hex: 0x10\nbad_big: 1e400\nbad_comma: 0,5\n"
      "bad_space: 1 2\nbad_over: 9223372036854775808\nbad_sign: +-3\ninf: -.inf\n",
      "n.yaml");
  EXPECT_EQ(root.child("a").number(), 5.0);
  EXPECT_EQ(root.child("b").number(), -0.5);
  EXPECT_EQ(root.child("c").number(), 5.0);
  EXPECT_EQ(root.child("d").number(), 1.0e5);
  EXPECT_EQ(root.child("e").number(), 2e-3);
  EXPECT_EQ(root.child("f").number(), 7.0);
  EXPECT_TRUE(std::signbit(root.child("g").number()));
  EXPECT_EQ(root.child("f").integer(), 7);
  EXPECT_EQ(root.child("i").integer(), 31);
  EXPECT_EQ(root.child("j").integer(), 15);
  EXPECT_EQ(root.child("k").integer(), std::numeric_limits<std::int64_t>::min());
  EXPECT_EQ(root.child("l").integer(), std::numeric_limits<std::int64_t>::max());
  EXPECT_EQ(root.child("m").integer(), 10);  // YAML 1.2: decimal (octal is 0o10)
  for (const char* key :
       {"bad_inf", "bad_nan", "bad_hex", "bad_big", "bad_comma", "bad_space", "bad_sign"}) {
    const auto e = config_error([&] { root.child(key).number(); });
    EXPECT_NE(std::string(e.what()).find(": expected a number, got '"), std::string::npos)
        << key << ": " << e.what();
  }
  for (const char* key : {"bad_over", "bad_sign", "d"}) {
    const auto e = config_error([&] { root.child(key).integer(); });
    EXPECT_NE(std::string(e.what()).find(": expected an integer, got '"), std::string::npos)
        << key << ": " << e.what();
  }
  EXPECT_EQ(std::string(config_error([&] { root.child("inf").number(); }).what()),
            "n.yaml: inf: expected a finite number, got '-.inf' (line 21)");
}

TEST(YamlReader, ChoosesFromANameTable) {
  enum class Shape { cube, ball };
  constexpr NameTable<Shape, 2> kShapes{{{"cube", Shape::cube}, {"ball", Shape::ball}}};
  EXPECT_STREQ(name_of(kShapes, Shape::ball), "ball");
  EXPECT_EQ(names_list(kShapes), "cube, ball");
  const YamlNode root = parse_yaml("a: ball\nb: cone\n", "shapes.yaml");
  EXPECT_EQ(root.child("a").choose(kShapes), Shape::ball);
  EXPECT_STREQ(config_error([&] { root.child("b").choose(kShapes); }).what(),
               "shapes.yaml: b: unknown value 'cone' (expected one of: cube, ball) (line 2)");
  EXPECT_STREQ(config_error([&] { root.child("b").choose(kShapes, "shape"); }).what(),
               "shapes.yaml: b: unknown shape 'cone' (expected one of: cube, ball) (line 2)");
}

TEST(YamlReader, SyntaxErrorNamesFileAndLine) {
  const auto e = config_error([] { parse_yaml("a: 1\nb: [unclosed\n", "bad.yaml"); });
  EXPECT_EQ(e.file(), "bad.yaml");
  EXPECT_EQ(e.field(), "");
  const std::string what = e.what();
  EXPECT_EQ(what.rfind("bad.yaml: YAML syntax error (not valid YAML): ", 0), 0u) << what;
  EXPECT_NE(what.find("(line "), std::string::npos) << what;
}

TEST(YamlReader, ReadsTextFiles) {
  const auto path = std::filesystem::temp_directory_path() / "sinew_yaml_reader_test.yaml";
  {
    std::ofstream out(path, std::ios::binary);
    out << "a: 1\n";
  }
  EXPECT_EQ(read_text_file(path, "test file"), "a: 1\n");
  std::filesystem::remove(path);
  try {
    read_text_file("/nonexistent/x.yaml", "test file");
    FAIL() << "expected an IoError";
  } catch (const IoError& e) {
    EXPECT_STREQ(e.what(),
                 "/nonexistent/x.yaml: cannot open the test file: No such file or directory");
  }
}

TEST(YamlReader, ReplacesValuesAtKeyPathsInACopyOfTheDocument) {
  const auto doc = parse_yaml(
      "a: 1\nb: {c: 2, d: [1, 2, 3]}\nlist:\n  - {x: 1}\n  - {x: 2}\nkeep: text\n", "doc.yaml");
  const auto values = parse_yaml("v1: 5\nv2: [7, 8]\nv3: {y: 3}\nv4: ~\nv5: 9\n", "sweep.yaml");
  const auto out = doc.replaced({{"a", values.child("v1")},
                                 {"b.d", values.child("v2")},
                                 {"list[1]", values.child("v3")},
                                 {"keep", values.child("v4")},
                                 {"b.new", values.child("v5")}});
  const auto r = parse_yaml(out, "out.yaml");
  EXPECT_EQ(r.child("a").integer(), 5);
  EXPECT_EQ(r.child("b").child("c").integer(), 2);
  EXPECT_EQ(r.child("b").child("d").emit(), "[7, 8]");
  EXPECT_EQ(r.child("b").child("new").integer(), 9);
  EXPECT_EQ(r.child("list").item(0).child("x").integer(), 1);
  EXPECT_EQ(r.child("list").item(1).emit(), "{y: 3}");
  EXPECT_FALSE(r.has("keep"));             // an empty value removes the key
  EXPECT_EQ(doc.child("a").integer(), 1);  // the original is unchanged

  const auto message = [&](const std::string& path) {
    try {
      doc.replaced({{path, values.child("v1")}});
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(message("list[2].x"),
            "sweep.yaml: v1: index 2 out of range at 'list[2]' (2 items) (line 1)");
  EXPECT_EQ(message("nothing.x"),
            "sweep.yaml: v1: no key 'nothing' at 'nothing' in the document (line 1)");
  EXPECT_EQ(message("a[0]"), "sweep.yaml: v1: 'a[0]' is not a list (line 1)");
  EXPECT_EQ(message("b..c"), "sweep.yaml: v1: malformed key path 'b..c' (line 1)");
  EXPECT_EQ(message("[0]"), "sweep.yaml: v1: malformed key path '[0]' (line 1)");
}

}  // namespace
}  // namespace sinew
