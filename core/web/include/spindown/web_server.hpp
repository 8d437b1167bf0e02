#pragma once
// spindown-web's HTTP side (cpp-httplib, Debian's libcpp-httplib-dev): the pages, the JSON, the
// CSV of a run, the live push and the assets, all GET; nothing controls a bench.
//
//   GET /                          the room page          GET /bench/<id>           a bench's page
//   GET /api/state                 every bench (JSON)     GET /api/bench/<id>       one bench
//   GET /api/bench/<id>/runs/<n>   one kept run           GET /bench/<id>/runs/<n>.csv  its samples
//   GET /events[?bench=<id>]       Server-Sent Events: a snapshot, then the changes
//   GET /assets/…                  scripts, style, icon, uPlot (built in: no CDN, no font download)
//
// Every request reads the lab under the caller's mutex (lab_mutex), the one the LCM side holds
// while it feeds the lab and publishes its updates, so a page's snapshot and the events after it
// are consecutive. Each event stream has an HTTP thread of its own (the pool holds
// max_clients + spare_threads), blocked only on its own socket.
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>
#include <string_view>

#include "spindown/event_fanout.hpp"
#include "spindown/web_lab.hpp"

namespace spindown {

struct WebServerOptions {
  std::string host = "127.0.0.1";
  int port = 8080;               // 0: any free port (bound_port() says which)
  int listen_fd = -1;            // >= 0: serve on this listening socket, inherited (host and port unused)
  std::size_t spare_threads = 16;  // beside one per event stream, for pages, JSON and assets
  double write_timeout_s = 5;    // a page that takes no bytes this long is dropped
  // A "tick" event on an idle event stream this often: the page calls itself stale when it hears
  // nothing for three of them, and a dead page's socket fails.
  double keepalive_s = 2;
  int backlog = 128;             // connections waiting to be accepted (a class opening the page at once)
  // Host names the pages may be asked for beside IP literals, "localhost" and this PC's own name
  // (--allow-host): any other Host header is refused (421), so a web page elsewhere whose name
  // resolves to this PC (DNS rebinding) cannot read the lab's data in a student's browser.
  std::vector<std::string> allow_hosts;
};

// Whether a request's Host header names this server: empty (HTTP/1.0), an IP literal (with or
// without a port), "localhost", this PC's host name (also with ".local"), or one of allowed.
bool host_allowed(std::string_view host_header, const std::vector<std::string>& allowed);

// "ADDR:PORT" → host and port: "0.0.0.0:8080", "192.168.1.10:80", "[::]:8080", "localhost:8080".
bool parse_listen_address(std::string_view text, std::string& host, int& port, std::string* why = nullptr);

class WebServer {
 public:
  WebServer(WebLab& lab, std::mutex& lab_mutex, EventFanout& fanout, WebServerOptions options);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  // Binds host:port (or takes listen_fd). False and *why when the address cannot be had (in use,
  // not this host's) or listen_fd is not a listening TCP socket.
  bool bind(std::string* why = nullptr);
  int bound_port() const;
  std::string bound_host() const;  // the address served on ("127.0.0.1", "::", …)
  // Serves on its own thread until stop().
  void start();
  void stop();
  bool running() const;

  std::int64_t requests() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace spindown
