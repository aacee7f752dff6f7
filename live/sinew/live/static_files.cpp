#include "sinew/live/static_files.hpp"

#include <filesystem>
#include <system_error>

namespace sinew::live {

namespace fs = std::filesystem;

namespace {

bool plain_segments(std::string_view rel) {
  std::size_t start = 0;
  while (start <= rel.size()) {
    const std::size_t end = std::min(rel.find('/', start), rel.size());
    const std::string_view seg = rel.substr(start, end - start);
    if (seg.empty() || seg.front() == '.') return false;
    for (char c : seg) {
      const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '.' || c == '_' || c == '-';
      if (!ok) return false;
    }
    start = end + 1;
  }
  return true;
}

}  // namespace

std::optional<std::string> resolve_static(const std::vector<StaticRoot>& roots,
                                          std::string_view target) {
  target = target.substr(0, target.find_first_of("?#"));
  if (target == "/") target = "/index.html";
  for (const auto& root : roots) {
    if (target.substr(0, root.prefix.size()) != root.prefix) continue;
    const std::string_view rel = target.substr(root.prefix.size());
    if (rel.empty() || rel.size() > 512 || !plain_segments(rel)) return std::nullopt;
    std::error_code ec;
    const fs::path base = fs::canonical(root.folder, ec);
    if (ec) continue;
    const fs::path file = fs::canonical(base / fs::path(rel), ec);
    if (ec || !fs::is_regular_file(file, ec)) continue;
    // Inside the folder after resolving symlinks (a link out of it is refused).
    const auto b = base.string() + "/";
    if (file.string().compare(0, b.size(), b) != 0) return std::nullopt;
    return file.string();
  }
  return std::nullopt;
}

std::string_view content_type(std::string_view path) {
  const auto ends = [&](std::string_view ext) {
    return path.size() >= ext.size() && path.substr(path.size() - ext.size()) == ext;
  };
  if (ends(".html")) return "text/html; charset=utf-8";
  if (ends(".js") || ends(".mjs")) return "text/javascript; charset=utf-8";
  if (ends(".css")) return "text/css; charset=utf-8";
  if (ends(".json")) return "application/json";
  if (ends(".png")) return "image/png";
  if (ends(".svg")) return "image/svg+xml";
  return "application/octet-stream";
}

}  // namespace sinew::live
