#pragma once
// The one YAML reader of the project: the voxelizer's spec files and the simulator's scene files
// both read their YAML through it (yaml-cpp stays inside yaml_reader.cpp).
//
// A YamlNode is a node of a parsed document together with its key path and the file name, so
// every check can throw a ConfigError that names the file, the key path and the line:
//
//   const YamlNode root = parse_yaml(text, "box.yaml");
//   root.allow_keys({"model", "output"});
//   const double dt = root.child("output").child("interval").non_negative();
//   -> "box.yaml: output.interval: must be >= 0, got -1 (line 7)"
//
// Key paths: "key" at the top, "parent.key" below, "list[2]" for list items (0-based). Lines are
// 1-based and appended to the problem as " (line N)"; a key that is absent has no line.
// A key whose value is empty (`key:` or `key: ~`) counts as absent (has() is false).
// YamlNode is a small value: copies share the parsed document, which lives as long as any node.
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sinew/common/error.hpp"
#include "sinew/common/names.hpp"

namespace YAML {
class Node;
}  // namespace YAML

namespace sinew {

struct YamlReplacement;

class YamlNode {
 public:
  // The file name given to parse_yaml, as written ("" for text without a file).
  const std::string& file() const;
  // The key path, "" for the document's root.
  const std::string& path() const;
  // 1-based line of the node in the file; none for an absent key.
  std::optional<int> line() const;

  bool defined() const;  // present and not empty
  bool is_map() const;
  bool is_sequence() const;
  bool is_scalar() const;
  std::size_t size() const;  // entries of a map or list; 0 otherwise

  // A ConfigError (file, path, problem + " (line N)") for the caller to throw.
  ConfigError error(const std::string& problem) const;

  // The value of `key` (absent when this is not a map or lacks the key) and list item i.
  YamlNode child(const std::string& key) const;
  YamlNode item(std::size_t i) const;
  bool has(const std::string& key) const;
  // The items of a list in order; none when this key is absent. "expected a list" when it is
  // present but not a list.
  std::vector<YamlNode> items() const;
  // child(key), or throws "missing key 'key'" (at this node's path) when it is absent.
  YamlNode require(const std::string& key) const;

  void expect_map() const;       // throws "expected a mapping of keys"
  void expect_sequence() const;  // throws "expected a list"
  // Every key must be one of `allowed`, else "unknown key 'k' (allowed here: ...)" at the key.
  void allow_keys(const std::vector<std::string_view>& allowed) const;
  // The keys of a map in file order. A key that is not a plain name, or one given twice, is an
  // error (YAML would otherwise keep only one of the two values).
  std::vector<std::string> keys() const;

  // Scalars. Each throws "expected ..., got '<text>'" when the value does not convert.
  std::string text() const;
  double number() const;        // finite
  double positive() const;      // > 0
  double non_negative() const;  // >= 0
  std::int64_t integer() const;
  bool boolean() const;
  std::array<double, 3> vec3() const;  // a list of exactly 3 numbers [x, y, z]

  // The node as YAML text on one line, in flow style ("0.5", "[0, 0, -9.81]", "{ramp: 0.1}").
  std::string emit() const;

  // Editing, for documents made from other documents (sinew-sweep writes one scene per run from
  // a base scene): this document (the node must be parse_yaml's root), copied, with the value at
  // each key path replaced by a copy of the given node, as YAML text (comments are not kept). A key path is
  // what path() gives: "damping", "muscles.frontalis_l.peak", "probes[2].point". Every map on the
  // way must exist and every list index must be in range; the last key of a map may be new (the
  // reader of the result checks it is allowed). A path that does not lead into the document
  // throws the ConfigError of the replacing node (its file and key): "no key 'x' at 'a.x' in the
  // document", "index 4 out of range at 'probes[4]' (3 items)", "malformed key path". An empty
  // value (`~`) for a map key removes the key, so the reader's default applies.
  std::string replaced(const std::vector<YamlReplacement>& replacements) const;

  // The value of a name table (names.hpp) whose name the text is, else
  // "unknown <what> '<text>' (expected one of: a, b, c)".
  template <typename T, std::size_t N>
  T choose(const NameTable<T, N>& options, std::string_view what = "value") const {
    const std::string s = text();
    for (const auto& [name, value] : options) {
      if (s == name) return value;
    }
    throw unknown_name(what, s, names_list(options));
  }

 private:
  friend YamlNode parse_yaml(const std::string& text, const std::string& file);
  struct State;
  explicit YamlNode(std::shared_ptr<const State> state);
  YamlNode derived(const YAML::Node& node, std::string path) const;
  ConfigError unknown_name(std::string_view what, const std::string& text,
                           const std::string& list) const;

  std::shared_ptr<const State> state_;
};

// One replacement for YamlNode::replaced(): the key path in the document and the new value.
struct YamlReplacement {
  std::string path;
  YamlNode value;
};

// Parses YAML text into its root node. `file` names the text in every message. A syntax error
// throws ConfigError(file, "", "YAML syntax error (not valid YAML): ... (line L, column C)"), and
// so does text that is not UTF-8 (YAML 1.2 is Unicode; yaml-cpp passes any byte on, and names and
// titles end up in JSON files and messages): "not UTF-8 text: byte 0x9C (line L, column C)".
YamlNode parse_yaml(const std::string& text, const std::string& file);

// The whole content of a file; IoError(path, "", ...) when it is missing ("cannot open the <what>:
// <reason>"), not a regular file (a folder, a FIFO, a device: require_regular_file) or unreadable.
std::string read_text_file(const std::filesystem::path& path, const std::string& what);

}  // namespace sinew
