#pragma once
// Static files of the page (docs/live.md, "Security"): a URL path maps to a file under one of the
// served folders or to nothing. Rejected: anything but plain path characters (no '%', '\\', NUL,
// query strings are cut off before), '..' or '.' segments, hidden names, and any file whose real
// path (symlinks resolved) is not inside the real path of its folder.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sinew::live {

struct StaticRoot {
  std::string prefix;  // URL prefix, "/" or "/vendor/three/"
  std::string folder;  // the folder it serves
};

// The file for a URL target ("/" is index.html), or none.
std::optional<std::string> resolve_static(const std::vector<StaticRoot>& roots,
                                          std::string_view target);

// The Content-Type of a file by its extension.
std::string_view content_type(std::string_view path);

}  // namespace sinew::live
