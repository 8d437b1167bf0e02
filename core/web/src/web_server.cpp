#include "spindown/web_server.hpp"

#include <atomic>
#include <charconv>
#include <chrono>
#include <fmt/format.h>
#include <thread>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <httplib.h>

#include "spindown/clock.hpp"
#include "spindown/fail_why.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/web_assets.hpp"

namespace spindown {

namespace {

// Scripts, styles, images and the event stream from this server only: nothing from a CDN, and a
// page that tried would say so in the browser's console.
constexpr const char* content_security_policy =
    "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; object-src 'none'; "
    "base-uri 'none'; frame-ancestors 'none'; form-action 'none'";

constexpr const char* json_type = "application/json; charset=utf-8";

void send_json(httplib::Response& res, const Json& j) {
  res.set_header("Cache-Control", "no-store");
  res.set_content(j.dump(-1, ' ', false, Json::error_handler_t::replace), json_type);
}

void not_found(httplib::Response& res, const std::string& what) {
  res.status = 404;
  res.set_content(what + "\n", "text/plain; charset=utf-8");
}

void send_asset(httplib::Response& res, const WebAsset& a) {
  res.set_header("Cache-Control", "no-cache");
  res.set_content(a.data.data(), a.data.size(), std::string(a.content_type));
}

std::optional<std::int32_t> run_number(const std::string& text) {
  std::int32_t n = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc() || end != text.data() + text.size() || n < 0) return std::nullopt;
  return n;
}


// The address and port a socket is bound to; false when fd is not a listening TCP socket.
bool listening_address(int fd, std::string& host, int& port) {
  int listening = 0;
  socklen_t len = sizeof listening;
  if (::getsockopt(fd, SOL_SOCKET, SO_ACCEPTCONN, &listening, &len) != 0 || !listening) return false;
  sockaddr_storage a{};
  len = sizeof a;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0) return false;
  char text[INET6_ADDRSTRLEN] = {};
  if (a.ss_family == AF_INET) {
    const auto* in = reinterpret_cast<const sockaddr_in*>(&a);
    ::inet_ntop(AF_INET, &in->sin_addr, text, sizeof text);
    port = ntohs(in->sin_port);
  } else if (a.ss_family == AF_INET6) {
    const auto* in = reinterpret_cast<const sockaddr_in6*>(&a);
    ::inet_ntop(AF_INET6, &in->sin6_addr, text, sizeof text);
    port = ntohs(in->sin6_port);
  } else {
    return false;
  }
  host = text;
  return true;
}

// A listening TCP socket on host:port (port 0: any) with its own backlog (cpp-httplib's is 5: a
// class opening the page at once found the queue full); -1 and *why when it cannot be had.
int open_listening_socket(const std::string& host, int port, int backlog, std::string* why) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  std::string h = host;
  if (h.size() > 2 && h.front() == '[' && h.back() == ']') h = h.substr(1, h.size() - 2);
  if (const int rc = ::getaddrinfo(h.empty() ? nullptr : h.c_str(), service.c_str(), &hints, &found); rc != 0) {
    if (why) *why = fmt::format("cannot listen on {}:{}: {}", host, port, ::gai_strerror(rc));
    return -1;
  }
  int fd = -1;
  std::string last = "no address";
  for (addrinfo* a = found; a && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, backlog) != 0) {
      last = std::strerror(errno);
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(found);
  if (fd < 0 && why)
    *why = fmt::format("cannot listen on {}:{} ({}: in use, or not an address of this host)", host, port, last);
  return fd;
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c);
  return s;
}

}  // namespace

bool parse_listen_address(std::string_view text, std::string& host, int& port, std::string* why) {
  const std::size_t colon = text.rfind(':');
  if (colon == std::string_view::npos || colon == 0)
    return fail_why(why, fmt::format("'{}' is not ADDR:PORT (e.g. 0.0.0.0:8080, 127.0.0.1:8080, [::]:8080)", text));
  std::string_view h = text.substr(0, colon), p = text.substr(colon + 1);
  if (h.size() >= 2 && h.front() == '[' && h.back() == ']') h = h.substr(1, h.size() - 2);
  int value = -1;
  const auto [end, ec] = std::from_chars(p.data(), p.data() + p.size(), value);
  if (ec != std::errc() || end != p.data() + p.size() || value < 0 || value > 65535)
    return fail_why(why, fmt::format("'{}': the port '{}' is not a number from 0 to 65535", text, p));
  if (h.empty()) return fail_why(why, fmt::format("'{}': no address before the port", text));
  host = std::string(h);
  port = value;
  return true;
}

bool host_allowed(std::string_view host_header, const std::vector<std::string>& allowed) {
  std::string_view h = host_header;
  while (!h.empty() && (h.back() == ' ' || h.back() == '\t')) h.remove_suffix(1);
  while (!h.empty() && (h.front() == ' ' || h.front() == '\t')) h.remove_prefix(1);
  if (h.empty()) return true;  // HTTP/1.0: no name to check
  if (h.front() == '[') {      // [v6]:port
    const auto close = h.find(']');
    if (close == std::string_view::npos) return false;
    const std::string v6(h.substr(1, close - 1));
    in6_addr a6{};
    return ::inet_pton(AF_INET6, v6.c_str(), &a6) == 1;
  }
  const auto colon = h.rfind(':');
  std::string name = lower(std::string(colon == std::string_view::npos ? h : h.substr(0, colon)));
  if (!name.empty() && name.back() == '.') name.pop_back();  // "localhost." is localhost
  in_addr a4{};
  if (::inet_pton(AF_INET, name.c_str(), &a4) == 1 || name == "localhost") return true;
  char self[256] = {};
  if (::gethostname(self, sizeof self - 1) == 0 && self[0]) {
    const std::string me = lower(self);
    if (name == me || name == me + ".local") return true;
  }
  return std::any_of(allowed.begin(), allowed.end(), [&](const std::string& a) { return lower(a) == name; });
}

// cpp-httplib's server, able to serve on a listening socket it did not open (one inherited from
// deploy/run-lab, which opens it outside the lab's private network namespace). Not in the anonymous
// namespace: Impl, which holds one, has external linkage.
class AdoptingServer : public httplib::Server {
 public:
  void adopt(int fd) { svr_sock_ = fd; }
};

struct WebServer::Impl {
  WebLab& lab;
  std::mutex& lab_mutex;
  EventFanout& fanout;
  WebServerOptions opt;
  AdoptingServer server;
  std::thread thread;
  int port = -1;
  std::string host;
  std::atomic<std::int64_t> requests{0};

  Impl(WebLab& l, std::mutex& m, EventFanout& f, WebServerOptions o) : lab(l), lab_mutex(m), fanout(f), opt(std::move(o)) {}

  void routes();
  void events(const httplib::Request& req, httplib::Response& res);
};

void WebServer::Impl::routes() {
  const std::size_t threads = fanout.options().max_clients + opt.spare_threads;
  server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  const auto write_s = static_cast<time_t>(opt.write_timeout_s);
  server.set_write_timeout(write_s, static_cast<time_t>((opt.write_timeout_s - double(write_s)) * 1e6));
  server.set_read_timeout(5, 0);
  server.set_keep_alive_timeout(5);
  server.set_keep_alive_max_count(100);
  server.set_payload_max_length(64 * 1024);  // GET only: a request has no business being larger
  server.set_default_headers({{"Content-Security-Policy", content_security_policy},
                              {"X-Content-Type-Options", "nosniff"},
                              {"Referrer-Policy", "no-referrer"}});
  server.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    ++requests;
    const std::string host = req.get_header_value("Host");
    if (host_allowed(host, opt.allow_hosts)) return httplib::Server::HandlerResponse::Unhandled;
    res.status = 421;  // Misdirected Request: not this server's name
    const std::string name = host.substr(0, std::min<std::size_t>(host.rfind(':'), 100));
    res.set_content(fmt::format("spindown-web: the page was asked for as '{}', which is not this PC's name; if the "
                                "lab reaches it by that name, start spindown-web with --allow-host {} (a page "
                                "elsewhere whose name resolves here may not read the lab's data)\n",
                                host.substr(0, 100), name),
                    "text/plain; charset=utf-8");
    return httplib::Server::HandlerResponse::Handled;
  });
  server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return;
    res.set_content(res.status == 404 ? fmt::format("not found: {} (the room page is /)\n", req.path)
                                      : fmt::format("error {}\n", res.status),
                    "text/plain; charset=utf-8");
  });

  server.Get("/", [](const httplib::Request&, httplib::Response& res) { send_asset(res, *find_web_asset("/")); });
  server.Get("/favicon.ico", [](const httplib::Request&, httplib::Response& res) {
    send_asset(res, *find_web_asset("/assets/icon.svg"));
  });
  server.Get(R"(/assets/(.+))", [](const httplib::Request& req, httplib::Response& res) {
    if (const WebAsset* a = find_web_asset(req.path)) return send_asset(res, *a);
    not_found(res, fmt::format("no asset {}", req.path));
  });
  server.Get(R"(/bench/([A-Za-z0-9_-]{1,32})/?)", [](const httplib::Request&, httplib::Response& res) {
    send_asset(res, *find_web_asset("/bench.html"));
  });
  server.Get(R"(/bench/([A-Za-z0-9_-]{1,32})/runs/([0-9]{1,9})\.csv)",
             [this](const httplib::Request& req, httplib::Response& res) {
               const std::string id = req.matches[1];
               const auto n = run_number(req.matches[2]);
               std::optional<std::string> csv;
               {
                 std::lock_guard lock(lab_mutex);
                 if (n) csv = lab.run_csv(id, *n);
               }
               if (!csv) return not_found(res, fmt::format("bench {} has no run {} kept", id, req.matches[2].str()));
               res.set_header("Content-Disposition", fmt::format("attachment; filename=\"{}-run{}.csv\"", id, *n));
               res.set_header("Cache-Control", "no-store");
               res.set_content(std::move(*csv), "text/csv; charset=utf-8");
             });
  server.Get("/api/state", [this](const httplib::Request&, httplib::Response& res) {
    Json j;
    {
      std::lock_guard lock(lab_mutex);
      j = lab.state_json(wall_us());
    }
    const EventFanoutCounters c = fanout.counters();
    j["clients"] = {{"connected", c.clients},       {"max", fanout.options().max_clients},
                    {"refused", c.refused},         {"resyncs", c.resyncs},
                    {"dropped_events", c.dropped_events}};
    send_json(res, j);
  });
  server.Get(R"(/api/bench/([A-Za-z0-9_-]{1,32}))", [this](const httplib::Request& req, httplib::Response& res) {
    std::optional<Json> j;
    {
      std::lock_guard lock(lab_mutex);
      j = lab.bench_json(req.matches[1].str(), wall_us());
    }
    if (!j) return not_found(res, fmt::format("no bench {} heard", req.matches[1].str()));
    send_json(res, *j);
  });
  server.Get(R"(/api/bench/([A-Za-z0-9_-]{1,32})/runs/([0-9]{1,9}))",
             [this](const httplib::Request& req, httplib::Response& res) {
               const auto n = run_number(req.matches[2]);
               std::optional<Json> j;
               {
                 std::lock_guard lock(lab_mutex);
                 if (n) j = lab.run_json(req.matches[1].str(), *n);
               }
               if (!j) return not_found(res, fmt::format("bench {} has no run {} kept", req.matches[1].str(),
                                                         req.matches[2].str()));
               send_json(res, *j);
             });
  server.Get("/events", [this](const httplib::Request& req, httplib::Response& res) { events(req, res); });
}

// One page's event stream: its snapshot, then what changes; a page that fell behind gets a new
// snapshot; a "tick" every keepalive_s when nothing happens (the page knows the stream is alive;
// a dead page's socket fails).
void WebServer::Impl::events(const httplib::Request& req, httplib::Response& res) {
  const std::string bench = req.get_param_value("bench");
  std::string why;
  if (!bench.empty() && !is_valid_bench_id(bench, &why)) {
    res.status = 400;
    res.set_content(fmt::format("bench '{}': {}\n", bench, why), "text/plain; charset=utf-8");
    return;
  }
  std::optional<EventFanout::ClientId> id;
  {
    std::lock_guard lock(lab_mutex);
    id = fanout.connect(bench, "retry: 2000\n\n" + lab.snapshot_event(bench, wall_us()));
  }
  if (!id) {
    const auto c = fanout.counters();
    res.status = 503;
    res.set_header("Retry-After", "10");
    res.set_content(fmt::format("spindown-web: {} pages are connected, the most it serves (--max-clients); "
                                "try again later\n",
                                c.clients),
                    "text/plain; charset=utf-8");
    return;
  }
  res.set_header("Cache-Control", "no-store");
  res.set_header("X-Accel-Buffering", "no");
  const auto keepalive = std::chrono::milliseconds(static_cast<std::int64_t>(opt.keepalive_s * 1000));
  res.set_chunked_content_provider(
      "text/event-stream",
      [this, client = *id, keepalive](std::size_t, httplib::DataSink& sink) {
        std::string out;
        switch (fanout.next(client, out, keepalive)) {
          case EventFanout::Next::closed: return false;
          case EventFanout::Next::resync: {
            std::lock_guard lock(lab_mutex);
            const auto b = fanout.bench_of(client);
            if (!b) return false;
            fanout.resync(client, lab.snapshot_event(*b, wall_us()));
            return true;
          }
          case EventFanout::Next::idle: out = fmt::format("event: tick\ndata: {}\n\n", wall_us()); break;
          case EventFanout::Next::events: break;
        }
        return sink.write(out.data(), out.size());
      },
      [this, client = *id](bool) { fanout.disconnect(client); });
}

WebServer::WebServer(WebLab& lab, std::mutex& lab_mutex, EventFanout& fanout, WebServerOptions options)
    : impl_(std::make_unique<Impl>(lab, lab_mutex, fanout, std::move(options))) {
  impl_->routes();
}

WebServer::~WebServer() { stop(); }

bool WebServer::bind(std::string* why) {
  impl_->host = impl_->opt.host;
  if (impl_->opt.listen_fd >= 0) {
    if (!listening_address(impl_->opt.listen_fd, impl_->host, impl_->port)) {
      if (why) *why = fmt::format("file descriptor {} is not a listening TCP socket", impl_->opt.listen_fd);
      return false;
    }
    impl_->server.adopt(impl_->opt.listen_fd);
    return true;
  }
  const int fd = open_listening_socket(impl_->opt.host, impl_->opt.port, impl_->opt.backlog, why);
  if (fd < 0) return false;
  std::string bound_host;
  if (!listening_address(fd, bound_host, impl_->port)) {
    ::close(fd);
    if (why) *why = fmt::format("cannot listen on {}:{}", impl_->opt.host, impl_->opt.port);
    return false;
  }
  impl_->server.adopt(fd);
  return true;
}

int WebServer::bound_port() const { return impl_->port; }

std::string WebServer::bound_host() const { return impl_->host; }

void WebServer::start() {
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
}

void WebServer::stop() {
  if (!impl_) return;
  impl_->fanout.close_all();
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

bool WebServer::running() const { return impl_->server.is_running(); }

std::int64_t WebServer::requests() const { return impl_->requests.load(); }

}  // namespace spindown
