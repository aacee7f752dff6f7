#pragma once
// Name tables: the one place where an enum's values get their names, for reading them from a
// file (YamlNode::choose) and for writing them (name_of), so the two directions cannot drift.
//
//   constexpr NameTable<Precision, 2> kPrecisionNames{{{"float", Precision::float32},
//                                                      {"double", Precision::float64}}};
//   name_of(kPrecisionNames, Precision::float32)  -> "float"
//   names_list(kPrecisionNames)                   -> "float, double"
#include <array>
#include <cstddef>
#include <string>
#include <utility>

namespace sinew {

template <typename T, std::size_t N>
using NameTable = std::array<std::pair<const char*, T>, N>;

// The name of `value`, or "?" when the table lacks it.
template <typename T, std::size_t N>
constexpr const char* name_of(const NameTable<T, N>& table, T value) {
  for (const auto& [name, v] : table) {
    if (v == value) return name;
  }
  return "?";
}

// Every name of the table in its order, joined by ", ".
template <typename T, std::size_t N>
std::string names_list(const NameTable<T, N>& table) {
  std::string list;
  for (const auto& entry : table) list.append(list.empty() ? "" : ", ").append(entry.first);
  return list;
}

}  // namespace sinew
