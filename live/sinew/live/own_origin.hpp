#pragma once
// Which Host and Origin headers name this server (docs/live.md, "Threat model"). A web page open in
// the user's browser can make the browser send requests to 127.0.0.1: through DNS rebinding (a
// name of its own that resolves to 127.0.0.1, so its requests carry `Host: evil.example`) or with a
// cross-origin WebSocket (which browsers allow, carrying `Origin: http://evil.example`). Loopback
// needs no token, so the server itself has to refuse both: a request is answered only when its Host
// is one of the server's own names with the server's port, and a WebSocket handshake only when its
// Origin is the server's own page.
//
// The server's own names: the loopback literals 127.0.0.1 and [::1], localhost, the bound address
// (--host), the address the connection arrived at (for a wildcard bind such as 0.0.0.0: the
// machine's address the browser used; an IP literal names no attacker's domain), and the names
// given by --allow-host. The port is always required, and must be the server's.
#include <string>
#include <string_view>
#include <vector>

namespace sinew::live {

struct OwnHost {
  unsigned short port = 0;
  std::string bound;               // the bound address (an IP literal, or "localhost")
  std::vector<std::string> names;  // further host names (--allow-host), any case
};

// The address in its one canonical text ("::ffff:10.0.0.5" becomes "10.0.0.5"), or "" when `ip` is
// not an IPv4 or IPv6 literal (no brackets, no zone).
std::string canonical_ip(std::string_view ip);

// Why a host name cannot be one of the server's names (--allow-host), or "" when it can: letters,
// digits, '-' and '.', not an IP literal, no port.
std::string host_name_problem(std::string_view name);

// Whether a Host header ("127.0.0.1:8080", "[::1]:8080", "localhost:8080") names this server.
// `local` is the address the connection arrived at (canonical or not; "" none).
bool is_own_host(std::string_view host, const OwnHost& own, std::string_view local);

// Whether an Origin header is this server's own page: "http://" and a Host is_own_host accepts,
// nothing after it ("null", file://, https:// and other hosts are not).
bool is_own_origin(std::string_view origin, const OwnHost& own, std::string_view local);

}  // namespace sinew::live
