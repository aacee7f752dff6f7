#include "sinew/live/own_origin.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstring>

namespace sinew::live {

namespace {

char lower(char c) {
  return c >= 'A' && c <= 'Z' ? char(c - 'A' + 'a') : c;
}

bool same_name(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(),
                                            [](char x, char y) { return lower(x) == lower(y); });
}

// Splits "host:port" / "[v6]:port" into the host (brackets removed) and the port text. False when
// the form is wrong: no port, an unbracketed colon, anything after the closing bracket but ":port".
// A bracketed host must be an IPv6 literal: "[localhost]" and "[127.0.0.1]" are no browser's.
bool split_authority(std::string_view authority, std::string_view& host, std::string_view& port) {
  if (!authority.empty() && authority.front() == '[') {
    const auto close = authority.find(']');
    if (close == std::string_view::npos || close + 1 >= authority.size() ||
        authority[close + 1] != ':')
      return false;
    host = authority.substr(1, close - 1);
    port = authority.substr(close + 2);
    return host.find(':') != std::string_view::npos && !canonical_ip(host).empty();
  }
  const auto colon = authority.find(':');
  if (colon == std::string_view::npos || authority.find(':', colon + 1) != std::string_view::npos)
    return false;
  host = authority.substr(0, colon);
  port = authority.substr(colon + 1);
  return true;
}

}  // namespace

std::string canonical_ip(std::string_view ip) {
  // inet_pton takes NUL-terminated text; anything longer than an IPv6 literal is not one.
  if (ip.empty() || ip.size() >= INET6_ADDRSTRLEN) return {};
  char text[INET6_ADDRSTRLEN] = {};
  std::memcpy(text, ip.data(), ip.size());
  char out[INET6_ADDRSTRLEN] = {};
  in_addr v4{};
  if (inet_pton(AF_INET, text, &v4) == 1)  // dotted quad only: "127.1" is no literal here
    return inet_ntop(AF_INET, &v4, out, sizeof out) ? out : "";
  in6_addr v6{};
  if (inet_pton(AF_INET6, text, &v6) != 1) return {};
  // A dual-stack socket reports IPv4 peers as ::ffff:a.b.c.d; the browser names them a.b.c.d.
  static constexpr std::array<unsigned char, 12> mapped{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff};
  if (std::memcmp(v6.s6_addr, mapped.data(), mapped.size()) == 0) {
    std::memcpy(&v4, v6.s6_addr + 12, 4);
    return inet_ntop(AF_INET, &v4, out, sizeof out) ? out : "";
  }
  return inet_ntop(AF_INET6, &v6, out, sizeof out) ? out : "";
}

std::string host_name_problem(std::string_view name) {
  if (name.empty()) return "an empty host name";
  if (name.size() > 253) return "a host name longer than 253 characters";
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.'))
      return "a host name has letters, digits, '-' and '.' only (no port, no brackets)";
  if (!canonical_ip(name).empty())
    return "an IP address, not a name (the bound address is allowed already)";
  return {};
}

bool is_own_host(std::string_view host, const OwnHost& own, std::string_view local) {
  std::string_view name, port;
  if (!split_authority(host, name, port)) return false;
  // The port exactly as a browser writes it: decimal, no sign, no leading zero.
  if (port != std::to_string(own.port)) return false;
  const std::string ip = canonical_ip(name);
  if (ip.empty()) {
    // A name: never an IP-looking one that failed to parse ("127.0.0.1.evil.example" is a name,
    // and it is not ours).
    if (same_name(name, "localhost")) return true;
    return std::any_of(own.names.begin(), own.names.end(),
                       [&](const std::string& n) { return same_name(name, n); });
  }
  // Unbracketed, an IP is IPv4 here (split_authority refused "::1:8080").
  if (ip == "127.0.0.1" || ip == "::1") return true;
  const std::string bound = canonical_ip(own.bound);
  if (!bound.empty() && ip == bound) return true;
  const std::string at = canonical_ip(local);
  return !at.empty() && ip == at;
}

bool is_own_origin(std::string_view origin, const OwnHost& own, std::string_view local) {
  // Browsers serialise the origin's scheme and host in lower case; "null" and file:// fail here.
  constexpr std::string_view scheme = "http://";
  if (origin.size() <= scheme.size() || !same_name(origin.substr(0, scheme.size()), scheme))
    return false;
  return is_own_host(origin.substr(scheme.size()), own, local);
}

}  // namespace sinew::live
