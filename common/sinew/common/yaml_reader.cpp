#include "sinew/common/yaml_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <type_traits>
#include <utility>

#include <fmt/format.h>

#include "sinew/common/input_file.hpp"

namespace sinew {

struct YamlNode::State {
  YAML::Node node;
  std::string path;
  std::shared_ptr<const std::string> file;  // shared by every node of one document
};

namespace {

// The length of the UTF-8 sequence at text[i] (RFC 3629: no overlong forms, no surrogates, nothing
// past U+10FFFF), or 0 when the bytes there are not one.
std::size_t utf8_length(const std::string& text, std::size_t i) {
  const auto byte = [&](std::size_t k) {
    return i + k < text.size() ? static_cast<unsigned char>(text[i + k]) : 0u;
  };
  const unsigned c = byte(0);
  if (c < 0x80) return 1;
  const auto cont = [&](std::size_t k, unsigned lo = 0x80, unsigned hi = 0xBF) {
    return byte(k) >= lo && byte(k) <= hi;
  };
  if (c >= 0xC2 && c <= 0xDF) return cont(1) ? 2 : 0;
  if (c == 0xE0) return cont(1, 0xA0) && cont(2) ? 3 : 0;
  if (c == 0xED) return cont(1, 0x80, 0x9F) && cont(2) ? 3 : 0;  // not the surrogates
  if (c >= 0xE1 && c <= 0xEF) return cont(1) && cont(2) ? 3 : 0;
  if (c == 0xF0) return cont(1, 0x90) && cont(2) && cont(3) ? 4 : 0;
  if (c >= 0xF1 && c <= 0xF3) return cont(1) && cont(2) && cont(3) ? 4 : 0;
  if (c == 0xF4) return cont(1, 0x80, 0x8F) && cont(2) && cont(3) ? 4 : 0;
  return 0;
}

void check_utf8(const std::string& text, const std::string& file) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < text.size();) {
    const auto n = utf8_length(text, i);
    if (n == 0) {
      throw ConfigError(file, "",
                        fmt::format("not UTF-8 text: byte 0x{:02X} (line {}, column {})",
                                    static_cast<unsigned char>(text[i]), line, column));
    }
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
    i += n;
  }
}

std::string join_key(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// yaml-cpp answers a lookup that finds nothing with an invalid "zombie" node on which most calls
// throw; an empty node answers the same questions (not defined, no line, size 0) without throwing.
YAML::Node or_empty(const YAML::Node& node) {
  return node.IsDefined() ? node : YAML::Node();
}

}  // namespace

YamlNode::YamlNode(std::shared_ptr<const State> state) : state_(std::move(state)) {}

YamlNode YamlNode::derived(const YAML::Node& node, std::string path) const {
  return YamlNode(std::make_shared<const State>(State{node, std::move(path), state_->file}));
}

const std::string& YamlNode::file() const {
  return *state_->file;
}
const std::string& YamlNode::path() const {
  return state_->path;
}

std::optional<int> YamlNode::line() const {
  const auto& n = state_->node;
  if (!n.IsDefined() || n.Mark().line < 0) return std::nullopt;
  return n.Mark().line + 1;
}

bool YamlNode::defined() const {
  return state_->node.IsDefined() && !state_->node.IsNull();
}
bool YamlNode::is_map() const {
  return state_->node.IsMap();
}
bool YamlNode::is_sequence() const {
  return state_->node.IsSequence();
}
bool YamlNode::is_scalar() const {
  return state_->node.IsScalar();
}
std::size_t YamlNode::size() const {
  return is_map() || is_sequence() ? state_->node.size() : 0;
}

ConfigError YamlNode::error(const std::string& problem) const {
  const auto l = line();
  return ConfigError(file(), path(), l ? fmt::format("{} (line {})", problem, *l) : problem);
}

YamlNode YamlNode::child(const std::string& key) const {
  const YAML::Node& n = state_->node;
  return derived(is_map() ? or_empty(n[key]) : YAML::Node(), join_key(path(), key));
}

YamlNode YamlNode::item(std::size_t i) const {
  const YAML::Node& n = state_->node;
  return derived(is_sequence() ? or_empty(n[i]) : YAML::Node(), fmt::format("{}[{}]", path(), i));
}

bool YamlNode::has(const std::string& key) const {
  return child(key).defined();
}

std::vector<YamlNode> YamlNode::items() const {
  std::vector<YamlNode> out;
  if (!defined()) return out;
  expect_sequence();
  for (std::size_t i = 0; i < size(); ++i) out.push_back(item(i));
  return out;
}

YamlNode YamlNode::require(const std::string& key) const {
  auto c = child(key);
  if (!c.defined()) throw error(fmt::format("missing key '{}'", key));
  return c;
}

void YamlNode::expect_map() const {
  if (!is_map()) throw error("expected a mapping of keys");
}

void YamlNode::expect_sequence() const {
  if (!is_sequence()) throw error("expected a list");
}

void YamlNode::allow_keys(const std::vector<std::string_view>& allowed) const {
  for (const auto& key : keys()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list.append(list.empty() ? "" : ", ").append(a);
      throw child(key).error(fmt::format("unknown key '{}' (allowed here: {})", key, list));
    }
  }
}

std::vector<std::string> YamlNode::keys() const {
  expect_map();
  std::vector<std::string> out;
  for (const auto& kv : state_->node) {
    if (!kv.first.IsScalar()) throw error("keys must be plain names");
    auto key = kv.first.Scalar();
    if (std::find(out.begin(), out.end(), key) != out.end()) {
      throw derived(kv.first, join_key(path(), key))
          .error(fmt::format("key '{}' given twice", key));
    }
    out.push_back(std::move(key));
  }
  return out;
}

std::string YamlNode::text() const {
  if (!is_scalar()) throw error("expected a text value");
  return state_->node.Scalar();
}

namespace {
// Numbers are read here, not by yaml-cpp's n.as<double>(), which goes through an istringstream and
// its locale's num_get facet: in the GPU machine's Python, once a NumPy wheel had been imported, that
// read crashed inside the facet (docs/python.md, "Known problem"). std::from_chars reads the same
// decimal text with no locale at all. YAML 1.2's core schema: [-+]?(.5|5|5.|5.5)([eE][-+]?5)? for
// floats, .inf/-.inf/.nan for the special values; [-+]?[0-9]+, 0x.. and 0o.. for integers.
std::optional<double> parse_double(std::string_view t) {
  if (t == ".nan" || t == ".NaN" || t == ".NAN") return std::numeric_limits<double>::quiet_NaN();
  bool negative = false;
  std::string_view body = t;
  if (!body.empty() && (body.front() == '+' || body.front() == '-')) {
    negative = body.front() == '-';
    body.remove_prefix(1);
  }
  if (body == ".inf" || body == ".Inf" || body == ".INF")
    return negative ? -std::numeric_limits<double>::infinity()
                    : std::numeric_limits<double>::infinity();
  // Digits, one point and an exponent only: from_chars alone would also take "inf" and "nan".
  if (body.empty() ||
      !(std::isdigit(static_cast<unsigned char>(body.front())) || body.front() == '.'))
    return std::nullopt;
  double v = 0;
  const auto [end, ec] =
      std::from_chars(body.data(), body.data() + body.size(), v, std::chars_format::general);
  if (ec != std::errc() || end != body.data() + body.size()) return std::nullopt;
  return negative ? -v : v;
}

std::optional<std::int64_t> parse_integer(std::string_view t) {
  bool negative = false;
  std::string_view body = t;
  if (!body.empty() && (body.front() == '+' || body.front() == '-')) {
    negative = body.front() == '-';
    body.remove_prefix(1);
  }
  int base = 10;
  if (body.size() > 2 && body[0] == '0' && (body[1] == 'x' || body[1] == 'o')) {
    base = body[1] == 'x' ? 16 : 8;
    body.remove_prefix(2);
  }
  if (body.empty() || body.front() == '-' || body.front() == '+') return std::nullopt;
  std::uint64_t magnitude = 0;
  const auto [end, ec] = std::from_chars(body.data(), body.data() + body.size(), magnitude, base);
  if (ec != std::errc() || end != body.data() + body.size()) return std::nullopt;
  const auto limit = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  if (magnitude > limit + (negative ? 1 : 0)) return std::nullopt;
  return negative ? static_cast<std::int64_t>(0 - magnitude) : static_cast<std::int64_t>(magnitude);
}

template <typename T>
std::optional<T> parse_scalar(const YAML::Node& n) {
  if constexpr (std::is_same_v<T, double>) {
    return parse_double(n.Scalar());
  } else if constexpr (std::is_same_v<T, std::int64_t>) {
    return parse_integer(n.Scalar());
  } else {
    try {
      return n.as<T>();  // bool: yaml-cpp compares words, no stream
    } catch (const YAML::Exception&) {
      return std::nullopt;
    }
  }
}

// The scalar as T, or the ConfigError "expected <what>, got '<text>'" from `at`.
template <typename T>
T convert(const YAML::Node& n, const YamlNode& at, const char* what) {
  if (!n.IsScalar()) throw at.error(fmt::format("expected {}", what));
  // yaml-cpp converts '0.001' as it does 0.001; a quoted scalar (tag "!") is a string in YAML, and
  // taking it for a number would hide a value the author meant as text (issue 33).
  if (n.Tag() == "!")
    throw at.error(fmt::format("expected {}, got the quoted string '{}' (write it without quotes)",
                               what, n.Scalar()));
  if (const auto v = parse_scalar<T>(n)) return *v;
  throw at.error(fmt::format("expected {}, got '{}'", what, n.Scalar()));
}
}  // namespace

double YamlNode::number() const {
  const double v = convert<double>(state_->node, *this, "a number");
  // yaml-cpp reads .nan and .inf as numbers; no quantity of a spec or scene may be one.
  if (!std::isfinite(v)) {
    throw error(fmt::format("expected a finite number, got '{}'", state_->node.Scalar()));
  }
  return v;
}

double YamlNode::positive() const {
  const double v = number();
  if (!(v > 0)) throw error(fmt::format("must be > 0, got {}", v));
  return v;
}

double YamlNode::non_negative() const {
  const double v = number();
  if (!(v >= 0)) throw error(fmt::format("must be >= 0, got {}", v));
  return v;
}

std::int64_t YamlNode::integer() const {
  return convert<std::int64_t>(state_->node, *this, "an integer");
}

bool YamlNode::boolean() const {
  return convert<bool>(state_->node, *this, "true or false");
}

std::array<double, 3> YamlNode::vec3() const {
  if (!is_sequence() || size() != 3) throw error("expected a list of 3 numbers [x, y, z]");
  return {item(0).number(), item(1).number(), item(2).number()};
}

ConfigError YamlNode::unknown_name(std::string_view what, const std::string& text,
                                   const std::string& list) const {
  return error(fmt::format("unknown {} '{}' (expected one of: {})", what, text, list));
}

std::string YamlNode::emit() const {
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << state_->node;
  return out.c_str();
}

namespace {

// One step of a key path: a map key or a list index.
struct PathStep {
  std::string key;
  std::optional<std::size_t> index;
};

// "a.b[2].c" -> a, b, [2], c; none for a malformed path.
std::optional<std::vector<PathStep>> split_key_path(const std::string& path) {
  std::vector<PathStep> steps;
  std::size_t i = 0;
  while (i < path.size()) {
    if (path[i] == '[') {
      const auto close = path.find(']', i);
      if (close == std::string::npos || close == i + 1 || steps.empty()) return std::nullopt;
      const auto digits = path.substr(i + 1, close - i - 1);
      if (!std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return std::nullopt;
      steps.push_back({"", std::stoul(digits)});
      i = close + 1;
      if (i < path.size() && path[i] != '.' && path[i] != '[') return std::nullopt;
      if (i < path.size() && path[i] == '.') ++i;
      continue;
    }
    const auto end = path.find_first_of(".[", i);
    const auto key = path.substr(i, end == std::string::npos ? std::string::npos : end - i);
    if (key.empty()) return std::nullopt;
    steps.push_back({key, std::nullopt});
    if (end == std::string::npos) break;
    i = path[end] == '.' ? end + 1 : end;
    if (path[end] == '.' && i == path.size()) return std::nullopt;
  }
  if (steps.empty()) return std::nullopt;
  return steps;
}

}  // namespace

std::string YamlNode::replaced(const std::vector<YamlReplacement>& replacements) const {
  if (!path().empty()) throw error("replaced() must be called on a document's root");
  // A deep copy of the document for the replacements to edit.
  YAML::Node doc = YAML::Clone(state_->node);
  for (const auto& r : replacements) {
    const auto steps = split_key_path(r.path);
    if (!steps) throw r.value.error(fmt::format("malformed key path '{}'", r.path));
    // Walk with raw node handles (yaml-cpp's operator[] on a non-const node would create keys).
    YAML::Node at = doc;
    std::string walked;
    for (std::size_t k = 0; k < steps->size(); ++k) {
      const auto& s = (*steps)[k];
      const bool last = k + 1 == steps->size();
      if (s.index) {
        walked += fmt::format("[{}]", *s.index);
        if (!at.IsSequence()) throw r.value.error(fmt::format("'{}' is not a list", walked));
        if (*s.index >= at.size()) {
          throw r.value.error(
              fmt::format("index {} out of range at '{}' ({} items)", *s.index, walked, at.size()));
        }
        if (last) {
          at[*s.index] = YAML::Clone(r.value.state_->node);
        } else {
          at.reset(at[*s.index]);
        }
        continue;
      }
      walked = join_key(walked, s.key);
      if (!at.IsMap()) {
        throw r.value.error(fmt::format("the document has no map at '{}' (for key '{}')",
                                        walked.substr(0, walked.size() - s.key.size()), s.key));
      }
      if (last && r.value.state_->node.IsNull()) {
        at.remove(s.key);  // an empty value removes the key: the reader's default applies
      } else if (last) {
        at[s.key] = YAML::Clone(r.value.state_->node);
      } else {
        const YAML::Node& cat = at;
        if (!cat[s.key].IsDefined() || cat[s.key].IsNull())
          throw r.value.error(fmt::format("no key '{}' at '{}' in the document", s.key, walked));
        at.reset(at[s.key]);
      }
    }
  }
  YAML::Emitter out;
  out << doc;
  return std::string(out.c_str()) + "\n";
}

YamlNode parse_yaml(const std::string& text, const std::string& file) {
  check_utf8(text, file);
  // One document a file: YAML::Load reads the first and drops the rest without a word. Found in
  // the text, not with YAML::LoadAll, which loops for ever on some damaged files (yaml-cpp 0.7,
  // found by the input fuzzer): a line starting a document (`---` at its start, then a blank or
  // the end) after content is a second document (YAML forbids the marker inside a scalar).
  {
    bool content = false;
    std::size_t line = 0, start = 0;
    while (start <= text.size()) {
      const std::size_t end = std::min(text.find('\n', start), text.size());
      const std::string_view l(text.data() + start, end - start);
      ++line;
      const bool marker =
          l.substr(0, 3) == "---" && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '\r');
      if (marker && content) {
        throw ConfigError(
            file, "",
            fmt::format("a second YAML document starts at line {}; give one document", line));
      }
      const auto first = l.find_first_not_of(" \t\r");
      if (!marker && first != std::string_view::npos && l[first] != '#') content = true;
      start = end + 1;
    }
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(file, "",
                      fmt::format("YAML syntax error (not valid YAML): {} (line {}, column {})",
                                  e.msg, e.mark.line + 1, e.mark.column + 1));
  }
  return YamlNode(std::make_shared<const YamlNode::State>(
      YamlNode::State{root, "", std::make_shared<const std::string>(file)}));
}

std::string read_text_file(const std::filesystem::path& path, const std::string& what) {
  require_regular_file(path, what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string(), "", "cannot open the " + what);
  std::stringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw IoError(path.string(), "", "cannot read the " + what);
  return ss.str();
}

}  // namespace sinew
