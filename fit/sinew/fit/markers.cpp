#include "sinew/fit/markers.hpp"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <set>

#include "sinew/common/error.hpp"
#include "sinew/common/yaml_reader.hpp"

namespace sinew::fit {
namespace {

// The file's field for an error at a line: "line 7" or "line 7, column 'chin.y'".
std::string where(int line, const std::string& column = {}) {
  return column.empty() ? fmt::format("line {}", line)
                        : fmt::format("line {}, column '{}'", line, column);
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return {};
  const auto b = s.find_last_not_of(" \t\r");
  return s.substr(a, b - a + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    cells.push_back(trim(line.substr(start, comma == std::string::npos ? std::string::npos
                                                                         : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return cells;
}

// A finite number, the whole cell; FormatError otherwise.
double number(const std::string& cell, const std::string& file, int line,
              const std::string& column) {
  double v = 0;
  const char* begin = cell.data();
  const char* end = cell.data() + cell.size();
  if (!cell.empty() && *begin == '+') ++begin;
  const auto [ptr, ec] = std::from_chars(begin, end, v);
  if (cell.empty() || ec != std::errc() || ptr != end)
    throw FormatError(file, where(line, column), fmt::format("not a number: '{}'", cell));
  if (!std::isfinite(v))
    throw FormatError(file, where(line, column), fmt::format("not a finite number: '{}'", cell));
  return v;
}

bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      return false;
  return true;
}

}  // namespace

std::size_t Markers::seen_count() const {
  std::size_t n = 0;
  for (const auto& row : seen)
    for (const bool s : row) n += s;
  return n;
}

Markers parse_markers(const std::string& text, const std::string& file) {
  Markers m;
  m.file = file;
  std::vector<std::string> header;
  int header_line = 0;
  int line_number = 0;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto nl = text.find('\n', start);
    const std::string raw =
        text.substr(start, nl == std::string::npos ? std::string::npos : nl - start);
    start = nl == std::string::npos ? text.size() + 1 : nl + 1;
    ++line_number;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const auto cells = split(line);
    if (header.empty()) {
      header = cells;
      header_line = line_number;
      m.header_line = line_number;
      if (header[0] != "time")
        throw FormatError(file, where(line_number, header[0]),
                          "the header's first column must be 'time' (docs/fit.md)");
      if ((header.size() - 1) % 3 != 0 || header.size() < 4)
        throw FormatError(file, where(line_number),
                          fmt::format("the header has {} columns after 'time': expected three "
                                      "per marker (NAME.x, NAME.y, NAME.z)",
                                      header.size() - 1));
      std::set<std::string> names;
      for (std::size_t c = 1; c < header.size(); c += 3) {
        const auto& col = header[c];
        const auto dot = col.rfind('.');
        const std::string name = dot == std::string::npos ? col : col.substr(0, dot);
        for (int d = 0; d < 3; ++d) {
          const std::string expected = name + "." + "xyz"[d];
          if (header[c + d] != expected)
            throw FormatError(file, where(line_number, header[c + d]),
                              fmt::format("expected column '{}' (a marker is three columns "
                                          "NAME.x, NAME.y, NAME.z)",
                                          expected));
        }
        if (!valid_name(name))
          throw FormatError(file, where(line_number, col),
                            fmt::format("marker name '{}': letters, digits, _, - and . only",
                                        name));
        if (!names.insert(name).second)
          throw FormatError(file, where(line_number, col),
                            fmt::format("marker '{}' appears twice", name));
        m.names.push_back(name);
      }
      continue;
    }
    if (cells.size() != header.size())
      throw FormatError(file, where(line_number),
                        fmt::format("{} cells, the header (line {}) has {}", cells.size(),
                                    header_line, header.size()));
    const double t = number(cells[0], file, line_number, "time");
    if (t < 0)
      throw FormatError(file, where(line_number, "time"),
                        fmt::format("time {} is before the scene's start (0 s)", cells[0]));
    if (!m.times.empty() && t <= m.times.back())
      throw FormatError(file, where(line_number, "time"),
                        fmt::format("time {} does not come after the previous row's {} (line {}): "
                                    "times must increase strictly",
                                    cells[0], m.times.back(), m.lines.back()));
    std::vector<std::array<double, 3>> row(m.names.size(), {0, 0, 0});
    std::vector<bool> seen(m.names.size(), false);
    for (std::size_t k = 0; k < m.names.size(); ++k) {
      const std::size_t c = 1 + 3 * k;
      const int empty = cells[c].empty() + cells[c + 1].empty() + cells[c + 2].empty();
      if (empty == 3) continue;
      if (empty != 0)
        throw FormatError(file, where(line_number, header[c]),
                          fmt::format("marker '{}' has {} of its 3 cells empty: a marker not seen "
                                      "leaves all three empty",
                                      m.names[k], empty));
      for (int d = 0; d < 3; ++d)
        row[k][d] = number(cells[c + d], file, line_number, header[c + d]);
      seen[k] = true;
    }
    m.times.push_back(t);
    m.lines.push_back(line_number);
    m.positions.push_back(std::move(row));
    m.seen.push_back(std::move(seen));
  }
  if (header.empty()) throw FormatError(file, "", "no header line (time,NAME.x,NAME.y,NAME.z,...)");
  if (m.times.empty()) throw FormatError(file, "", "no frames after the header");
  return m;
}

Markers read_markers(const std::string& path) {
  return parse_markers(read_text_file(path, "marker file"), path);
}

std::string markers_csv(const Markers& m) {
  std::string out = "time";
  for (const auto& n : m.names) out += fmt::format(",{0}.x,{0}.y,{0}.z", n);
  out += '\n';
  for (std::size_t f = 0; f < m.times.size(); ++f) {
    out += fmt::format("{:.17g}", m.times[f]);
    for (std::size_t k = 0; k < m.names.size(); ++k) {
      if (!m.seen[f][k]) {
        out += ",,,";
        continue;
      }
      for (int d = 0; d < 3; ++d) out += fmt::format(",{:.17g}", m.positions[f][k][d]);
    }
    out += '\n';
  }
  return out;
}

}  // namespace sinew::fit
