#include "sinew/live/server.hpp"

#include <atomic>
#include <cctype>
#include <chrono>
#include <deque>
#include <fstream>
#include <random>
#include <sstream>

#include <fmt/format.h>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "sinew/common/error.hpp"
#include "sinew/common/log.hpp"
#include "sinew/live/own_origin.hpp"

namespace sinew::live {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kAcceptRetry{100};

bool is_loopback_host(const std::string& host) {
  if (host == "localhost") return true;
  boost::system::error_code ec;
  const auto a = net::ip::make_address(host, ec);
  return !ec && a.is_loopback();
}

std::string make_token() {
  std::random_device rd;
  std::string t;
  for (int k = 0; k < 4; ++k) t += fmt::format("{:08x}", rd());
  return t;
}

std::string token_problem(const std::string& token) {
  if (token.size() < kMinTokenLength)
    return fmt::format(
        "an access token of {} characters is guessed quickly: give at least {} (sinew-live makes "
        "one of 32 random hex digits when --token is not given)",
        token.size(), kMinTokenLength);
  if (token.size() > 256) return "an access token longer than 256 characters";
  for (const char c : token)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' || c == '_' ||
          c == '~'))
      return "an access token has letters, digits, '-', '.', '_' and '~' only (it travels in the "
             "URL and a cookie as it is)";
  return {};
}

namespace {

bool same_token(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  unsigned char d = 0;
  for (std::size_t i = 0; i < a.size(); ++i) d |= static_cast<unsigned char>(a[i] ^ b[i]);
  return d == 0;
}

std::string query_value(std::string_view target, std::string_view key) {
  const auto q = target.find('?');
  if (q == std::string_view::npos) return {};
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const auto amp = rest.find('&');
    const std::string_view kv = rest.substr(0, amp);
    if (kv.size() > key.size() && kv.substr(0, key.size()) == key && kv[key.size()] == '=')
      return std::string(kv.substr(key.size() + 1));
    if (amp == std::string_view::npos) break;
    rest = rest.substr(amp + 1);
  }
  return {};
}

// The value of cookie `name` in a Cookie header ("a=1; b=2"), "" when absent.
std::string cookie_value(std::string_view header, std::string_view name) {
  while (!header.empty()) {
    const auto semi = header.find(';');
    std::string_view kv = header.substr(0, semi);
    while (!kv.empty() && kv.front() == ' ') kv.remove_prefix(1);
    if (kv.size() > name.size() && kv.substr(0, name.size()) == name && kv[name.size()] == '=')
      return std::string(kv.substr(name.size() + 1));
    if (semi == std::string_view::npos) break;
    header.remove_prefix(semi + 1);
  }
  return {};
}

}  // namespace

class WsClient;

struct Server::Impl : std::enable_shared_from_this<Server::Impl> {
  Impl(Session& s, ServerOptions o) : session(s), options(std::move(o)), acceptor(ioc) {}
  Session& session;
  ServerOptions options;
  net::io_context ioc{1};
  tcp::acceptor acceptor;
  std::vector<std::shared_ptr<WsClient>> clients;  // I/O thread only; front() steers
  std::atomic<std::size_t> client_count{0};
  // The clients joined plus the handshakes admitted and not finished (I/O thread only): a slot is
  // taken before the 101 is sent, so handshakes read together cannot all pass max_clients.
  std::size_t admitted = 0;
  OwnHost own;  // the names a Host or Origin may give (set once bound)
  // When accept() fails for want of descriptors (EMFILE, ENFILE) the listening socket stays
  // readable: retrying at once spins a core. It waits this timer instead, and says so once.
  net::steady_timer accept_retry{ioc};
  bool accept_failing = false;
  // The cookie that carries the token for the page's own requests (its scripts, styles and
  // three.js, which the URL's ?token= does not reach): named by the port, so two servers on one
  // host (cookies ignore ports) keep theirs apart. Set once bound.
  std::string cookie;

  void accept();
  bool admit() {
    if (admitted >= options.max_clients) return false;
    ++admitted;
    return true;
  }
  void release_slot() { --admitted; }
  void join(const std::shared_ptr<WsClient>& c);
  void leave(WsClient* c);
  bool steers(const WsClient* c) const { return !clients.empty() && clients.front().get() == c; }
  void broadcast(std::shared_ptr<const std::string> msg, bool binary);
  // `local`: the address the connection arrived at.
  bool own_host(const http::request<http::string_body>& req, const std::string& local) const {
    if (req.count(http::field::host) != 1) return false;
    const auto h = req[http::field::host];
    return is_own_host(std::string_view(h.data(), h.size()), own, local);
  }
  bool own_origin(const http::request<http::string_body>& req, const std::string& local) const {
    const auto n = req.count(http::field::origin);
    // No browser leaves the Origin out of a WebSocket handshake: without one it is a program,
    // let in only when it showed the token (authorized() passed).
    if (n == 0) return !options.token.empty();
    if (n != 1) return false;
    const auto o = req[http::field::origin];
    return is_own_origin(std::string_view(o.data(), o.size()), own, local);
  }
  bool authorized(const http::request<http::string_body>& req) const {
    if (options.token.empty()) return true;
    const auto auth = req[http::field::authorization];
    if (auth.size() > 7 && auth.substr(0, 7) == "Bearer " &&
        same_token(std::string_view(auth.data() + 7, auth.size() - 7), options.token))
      return true;
    const auto header = req[http::field::cookie];
    if (same_token(cookie_value(std::string_view(header.data(), header.size()), cookie),
                   options.token))
      return true;
    return same_token(
        query_value(std::string_view(req.target().data(), req.target().size()), "token"),
        options.token);
  }
};

class WsClient : public std::enable_shared_from_this<WsClient> {
 public:
  WsClient(tcp::socket socket, std::shared_ptr<Server::Impl> server)
      : ws_(std::move(socket)), server_(std::move(server)) {}

  void start(http::request<http::string_body> req) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxMessageBytes);
    // The slot admit() took is this client's from here: given back on failure or at leave().
    ws_.async_accept(req, [self = shared_from_this()](beast::error_code ec) {
      if (ec) {
        self->server_->release_slot();
        return;
      }
      self->open_ = true;
      self->server_->join(self);
      self->read();
    });
  }

  // I/O thread. Frames take the one frame slot (droppable); other messages queue in order.
  void send(std::shared_ptr<const std::string> msg, bool binary, bool droppable) {
    if (!open_) return;
    if (droppable) {
      if (frame_) ++dropped_;
      frame_ = std::move(msg);
    } else {
      if (queue_.size() >= server_->options.max_queued) {
        close("too slow: more than the queue limit behind");
        return;
      }
      queue_.push_back({std::move(msg), binary});
    }
    if (!writing_) write_next();
  }
  void send(std::shared_ptr<const std::string> msg, bool binary) {
    send(std::move(msg), binary, binary);
  }
  void send_text(const std::string& s) { send(std::make_shared<const std::string>(s), false); }

  void close(const std::string& why) {
    if (!open_) return;
    open_ = false;
    server_->leave(this);
    ws_.async_close(websocket::close_reason(websocket::close_code::policy_error, why),
                    [self = shared_from_this()](beast::error_code) {});
  }

 private:
  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->on_read(ec);
    });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      // Closed, broken, or a message above read_message_max (closed with code 1009, too big).
      if (open_) {
        open_ = false;
        server_->leave(this);
      }
      return;
    }
    const bool text = ws_.got_text();
    std::string message = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    if (!text)
      send_text(error_message("binary messages are not accepted; send JSON text"));
    else
      handle(message);
    if (open_) read();
  }

  void handle(const std::string& text) {
    const auto now = Clock::now();
    if (now - window_ > std::chrono::seconds(1)) {
      window_ = now;
      count_ = 0;
      warned_ = false;
    }
    if (++count_ > server_->options.max_messages_per_second) {
      if (!warned_)
        send_text(
            error_message(fmt::format("more than {:.0f} messages per second: the rest of "
                                      "this second's messages are dropped",
                                      server_->options.max_messages_per_second)));
      warned_ = true;
      return;
    }
    std::uint32_t id = 0;
    try {
      const Command c = parse_command(text);
      id = c.id;
      if (!server_->steers(this))
        throw ProtocolError("another client steers this session; this one watches");
      server_->session.submit(c);
    } catch (const ProtocolError& e) {
      send_text(error_message(e.message, id));
    }
  }

  void write_next() {
    std::shared_ptr<const std::string> msg;
    bool binary = false;
    if (!queue_.empty()) {
      msg = std::move(queue_.front().first);
      binary = queue_.front().second;
      queue_.pop_front();
    } else if (frame_) {
      msg = std::move(frame_);
      binary = true;
    }
    if (!msg || !open_) {
      writing_ = false;
      return;
    }
    writing_ = true;
    ws_.binary(binary);
    ws_.async_write(net::buffer(*msg),
                    [self = shared_from_this(), msg](beast::error_code ec, std::size_t) {
                      if (ec) {
                        self->writing_ = false;
                        if (self->open_) {
                          self->open_ = false;
                          self->server_->leave(self.get());
                        }
                        return;
                      }
                      self->write_next();
                    });
  }

  websocket::stream<beast::tcp_stream> ws_;
  std::shared_ptr<Server::Impl> server_;
  beast::flat_buffer buffer_;
  std::deque<std::pair<std::shared_ptr<const std::string>, bool>> queue_;
  std::shared_ptr<const std::string> frame_;
  bool writing_ = false, open_ = false, warned_ = false;
  std::uint64_t dropped_ = 0;
  Clock::time_point window_{};
  double count_ = 0;
};

namespace {

class HttpClient : public std::enable_shared_from_this<HttpClient> {
 public:
  HttpClient(tcp::socket socket, std::shared_ptr<Server::Impl> server)
      : stream_(std::move(socket)), server_(std::move(server)) {
    beast::error_code ec;
    const auto at = stream_.socket().local_endpoint(ec);
    if (!ec) local_ = at.address().to_string();
  }

  void read() {
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(16 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(
        stream_, buffer_, *parser_,
        [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec != http::error::end_of_stream && ec != beast::error::timeout)
        reply(http::status::bad_request, "bad request: " + ec.message(), false);
      else
        stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
      return;
    }
    request_ = parser_->release();
    // The Host first: a page that made its own name resolve to this machine (DNS rebinding) gets
    // nothing, not even the token check's answer.
    if (!server_->own_host(request_, local_)) {
      reply(http::status::forbidden,
            "wrong Host: this server answers to 127.0.0.1, localhost, [::1] and its bound address, "
            "with its port (sinew-live --allow-host NAME adds a name)",
            false);
      return;
    }
    if (!server_->authorized(request_)) {
      reply(http::status::forbidden,
            "missing or wrong access token (open the URL sinew-live printed, with ?token=...)",
            false);
      return;
    }
    const std::string_view target(request_.target().data(), request_.target().size());
    const std::string_view path = target.substr(0, target.find('?'));
    if (websocket::is_upgrade(request_)) {
      if (path != "/ws") {
        reply(http::status::not_found, "no WebSocket here (use /ws)", false);
        return;
      }
      if (!server_->own_origin(request_, local_)) {
        reply(http::status::forbidden,
              "cross-origin WebSocket refused: only this server's own page may connect", false);
        return;
      }
      if (!server_->admit()) {
        reply(http::status::service_unavailable, "too many clients", false);
        return;
      }
      stream_.expires_never();
      std::make_shared<WsClient>(stream_.release_socket(), server_)->start(std::move(request_));
      return;
    }
    if (request_.method() != http::verb::get && request_.method() != http::verb::head) {
      reply(http::status::method_not_allowed, "only GET and HEAD", false);
      return;
    }
    const auto file = resolve_static(server_->options.roots, target);
    if (!file) {
      reply(http::status::not_found, "not found", request_.keep_alive());
      return;
    }
    std::ifstream in(*file, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    if (!in && !in.eof()) {
      reply(http::status::internal_server_error, "cannot read the file", false);
      return;
    }
    auto res =
        std::make_shared<http::response<http::string_body>>(http::status::ok, request_.version());
    res->set(http::field::content_type, std::string(content_type(*file)));
    res->set(http::field::cache_control, "no-store");
    res->set("X-Content-Type-Options", "nosniff");
    // The page's later requests carry the token by this cookie (HttpOnly: no script reads it;
    // SameSite=Strict: no other site's page sends it).
    if (!server_->options.token.empty())
      res->set(http::field::set_cookie, fmt::format("{}={}; Path=/; HttpOnly; SameSite=Strict",
                                                    server_->cookie, server_->options.token));
    res->keep_alive(request_.keep_alive());
    if (request_.method() == http::verb::get) res->body() = ss.str();
    res->prepare_payload();
    if (request_.method() == http::verb::head) res->content_length(ss.str().size());
    write(res);
  }

  void reply(http::status status, const std::string& text, bool keep_alive) {
    auto res = std::make_shared<http::response<http::string_body>>(status, 11);
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    res->set("X-Content-Type-Options", "nosniff");
    res->keep_alive(keep_alive);
    res->body() = text + "\n";
    res->prepare_payload();
    write(res);
  }

  void write(std::shared_ptr<http::response<http::string_body>> res) {
    http::async_write(stream_, *res,
                      [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
                        if (!ec && res->keep_alive()) {
                          self->read();
                          return;
                        }
                        self->stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
                      });
  }

  beast::tcp_stream stream_;
  std::shared_ptr<Server::Impl> server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  http::request<http::string_body> request_;
  std::string local_;  // the address the connection arrived at (own_host, own_origin)
};

// accept() failures that last until some descriptor or memory is freed; others (a connection reset
// before it was accepted) concern one connection, and the next accept goes on at once.
bool out_of_resources(const beast::error_code& ec) {
  namespace errc = boost::system::errc;
  return ec == errc::too_many_files_open || ec == errc::too_many_files_open_in_system ||
         ec == errc::no_buffer_space || ec == errc::not_enough_memory;
}

}  // namespace

void Server::Impl::accept() {
  acceptor.async_accept(
      net::make_strand(ioc), [self = shared_from_this()](beast::error_code ec, tcp::socket socket) {
        if (ec == net::error::operation_aborted) return;
        if (!ec && self->accept_failing) {
          self->accept_failing = false;
          log::info("sinew-live: accepting connections again");
        }
        if (!ec) std::make_shared<HttpClient>(std::move(socket), self)->read();
        if (!self->acceptor.is_open()) return;
        if (!out_of_resources(ec)) {
          self->accept();
          return;
        }
        if (!self->accept_failing)
          log::warn(
              "sinew-live: cannot accept a connection ({}): trying again every {} ms until it can "
              "(raise `ulimit -n`, or close other clients)",
              ec.message(), kAcceptRetry.count());
        self->accept_failing = true;
        self->accept_retry.expires_after(kAcceptRetry);
        self->accept_retry.async_wait([self](beast::error_code wait) {
          if (!wait && self->acceptor.is_open()) self->accept();
        });
      });
}

void Server::Impl::join(const std::shared_ptr<WsClient>& c) {
  clients.push_back(c);
  client_count = clients.size();
  c->send_text(session.hello_json());
  c->send(session.mesh_message(), true, false);  // in order: before any frame
  c->send_text(fmt::format("{{\"type\": \"role\", \"steering\": {}}}", steers(c.get())));
  if (auto s = session.latest_status()) c->send(s, false);
  if (auto f = session.latest_frame()) c->send(f, true);
}

void Server::Impl::leave(WsClient* c) {
  const bool was_steering = steers(c);
  std::erase_if(clients, [&](const auto& p) { return p.get() == c; });
  client_count = clients.size();
  release_slot();
  if (was_steering && !clients.empty())
    clients.front()->send_text("{\"type\": \"role\", \"steering\": true}");
}

void Server::Impl::broadcast(std::shared_ptr<const std::string> msg, bool binary) {
  const auto copy = clients;  // a send may close a client
  for (const auto& c : copy) c->send(msg, binary);
}

Server::Server(Session& session, ServerOptions options)
    : impl_(std::make_shared<Impl>(session, std::move(options))) {
  auto& o = impl_->options;
  if (!o.token.empty())
    if (const auto problem = token_problem(o.token); !problem.empty())
      throw ConfigError("", "--token", problem);
  for (auto& name : o.allowed_hosts)
    if (const auto problem = host_name_problem(name); !problem.empty())
      throw ConfigError("", "--allow-host", fmt::format("'{}': {}", name, problem));
  beast::error_code ec;
  const auto address = net::ip::make_address(o.host == "localhost" ? "127.0.0.1" : o.host, ec);
  if (ec) throw ConfigError("", "--host", fmt::format("'{}' is not an IP address", o.host));
  const tcp::endpoint ep(address, o.port);
  auto& a = impl_->acceptor;
  a.open(ep.protocol(), ec);
  if (!ec) a.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) a.bind(ep, ec);
  if (!ec) a.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw IoError(fmt::format("{}:{}", o.host, o.port), "", "cannot listen: " + ec.message());
  impl_->cookie = fmt::format("sinew_live_{}", port());
  impl_->own = {port(), o.host, o.allowed_hosts};
  std::weak_ptr<Impl> weak = impl_;
  session.set_sink([weak](std::shared_ptr<const std::string> msg, bool binary) {
    if (auto s = weak.lock()) net::post(s->ioc, [s, msg, binary] { s->broadcast(msg, binary); });
  });
  impl_->accept();
}

Server::~Server() {
  impl_->session.set_sink(nullptr);
  if (!impl_->ioc.stopped()) {
    stop();
    return;
  }
  beast::error_code ec;
  impl_->acceptor.close(ec);
  impl_->clients.clear();  // they hold the Impl
}

unsigned short Server::port() const {
  beast::error_code ec;
  return impl_->acceptor.local_endpoint(ec).port();
}

std::size_t Server::client_count() const {
  return impl_->client_count.load();
}

void Server::run(bool with_signals) {
  std::optional<net::signal_set> signals;
  if (with_signals) {
    signals.emplace(impl_->ioc, SIGINT, SIGTERM);
    signals->async_wait([this](beast::error_code ec, int) {
      if (!ec) stop();
    });
  }
  impl_->ioc.run();
}

void Server::stop() {
  auto s = impl_;
  net::post(s->ioc, [s] {
    beast::error_code ec;
    s->acceptor.close(ec);
    s->accept_retry.cancel();
    const auto clients = s->clients;
    for (const auto& c : clients) c->close("server stopping");
    s->ioc.stop();
  });
}

}  // namespace sinew::live
