// spindown-web over real HTTP on the loopback interface (no LCM: messages are fed as LCM's thread
// feeds them): the pages and assets come from the program itself, the JSON carries the FIT's own
// numbers, the event stream starts with a snapshot and then pushes a FIT, a page past the cap is
// refused, a refused (unverified) or broken message is never shown.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include <httplib.h>

#include "spindown/web_assets.hpp"
#include "spindown/web_service.hpp"
#include "web_test_support.hpp"

namespace spindown {
namespace {

using namespace spindown::test;
using namespace std::chrono_literals;

template <class Msg>
std::vector<unsigned char> encoded(const Msg& m) {
  std::vector<unsigned char> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

template <class Msg>
void feed(WebService& s, const std::string& channel, const Msg& m, std::int64_t now) {
  const auto b = encoded(m);
  s.take(channel, b.data(), static_cast<std::int64_t>(b.size()), now);
}

// A service on 127.0.0.1 at a free port, serving without LCM.
struct Served {
  explicit Served(WebServiceOptions o = {}) {
    o.server.host = "127.0.0.1";
    o.server.port = 0;
    service = std::make_unique<WebService>(std::move(o));
    WebServerOptions so;
    so.host = "127.0.0.1";
    so.port = 0;
    server = std::make_unique<WebServer>(service->lab(), service->mutex(), service->fanout(), so);
    std::string why;
    EXPECT_TRUE(server->bind(&why)) << why;
    server->start();
    for (int i = 0; i < 200 && !server->running(); ++i) std::this_thread::sleep_for(10ms);
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", server->bound_port());
    c.set_read_timeout(10, 0);
    return c;
  }
  std::unique_ptr<WebService> service;
  std::unique_ptr<WebServer> server;
};

std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(WebService, PagesAssetsJsonAndCsvComeFromTheProgramItself) {
  Served s;
  const SimulatedRun r = simulated_run();
  {
    std::lock_guard lock(s.service->mutex());
    feed_run(s.service->lab(), r);
  }
  auto c = s.client();
  auto room = c.Get("/");
  ASSERT_TRUE(room);
  EXPECT_EQ(room->status, 200);
  EXPECT_NE(room->get_header_value("Content-Type").find("text/html"), std::string::npos);
  EXPECT_NE(room->body.find("/assets/room.js"), std::string::npos);
  EXPECT_EQ(room->body.find("http"), std::string::npos) << "the room page loads nothing from elsewhere";
  EXPECT_NE(room->get_header_value("Content-Security-Policy").find("default-src 'self'"), std::string::npos);
  auto bench = c.Get("/bench/b1");
  ASSERT_TRUE(bench);
  EXPECT_EQ(bench->status, 200);
  EXPECT_NE(bench->body.find("data-plot"), std::string::npos);
  // uPlot exactly as vendored, with its licence.
  auto uplot = c.Get("/assets/uplot/uPlot.iife.min.js");
  ASSERT_TRUE(uplot);
  EXPECT_EQ(uplot->status, 200);
  EXPECT_EQ(uplot->body, file_text(std::string(SPINDOWN_SOURCE_DIR) + "/third_party/uplot/uPlot.iife.min.js"));
  auto licence = c.Get("/assets/uplot/LICENSE");
  ASSERT_TRUE(licence);
  EXPECT_NE(licence->body.find("MIT"), std::string::npos);
  for (const WebAsset& a : web_assets()) {
    const std::string path = a.path == "/bench.html" ? "/bench/b1" : std::string(a.path);  // the bench page's URL
    auto got = c.Get(path);
    ASSERT_TRUE(got) << path;
    EXPECT_EQ(got->status, 200) << path;
    EXPECT_EQ(got->body, a.data) << path;
    // No page, script or style names another host (a CDN, a font service); the icon's SVG
    // namespace is a name, not a fetch.
    if (a.path.find("uplot") == std::string_view::npos && a.path.find(".svg") == std::string_view::npos) {
      EXPECT_EQ(got->body.find("://"), std::string::npos) << a.path;
    }
  }
  // The state: the FIT's own numbers.
  auto state = c.Get("/api/state");
  ASSERT_TRUE(state);
  const Json j = Json::parse(state->body);
  ASSERT_EQ(j["benches"].size(), 1u);
  EXPECT_EQ(j["benches"][0]["last_fit"]["c3"]["value"].get<double>(), fit_param(r.fit, "combined", "c3"));
  EXPECT_EQ(j["benches"][0]["last_fit"]["c4"]["stderr"].get<double>() > 0, true);
  // The run's CSV.
  auto csv = c.Get("/bench/b1/runs/1.csv");
  ASSERT_TRUE(csv);
  EXPECT_EQ(csv->status, 200);
  EXPECT_EQ(csv->body.rfind("t_s,value\n", 0), 0u);
  EXPECT_EQ(static_cast<std::int64_t>(std::count(csv->body.begin(), csv->body.end(), '\n')) - 1,
            j["benches"][0]["run"]["samples"].get<std::int64_t>());
  auto missing = c.Get("/bench/b1/runs/7.csv");
  ASSERT_TRUE(missing);
  EXPECT_EQ(missing->status, 404);
  EXPECT_EQ(c.Get("/nothing")->status, 404);
  EXPECT_EQ(c.Get("/bench/../etc/passwd")->status, 404);
  // Only shows data: nothing to post to.
  auto post = c.Post("/api/state", "x", "text/plain");
  ASSERT_TRUE(post);
  EXPECT_GE(post->status, 400);
}

// Reads /events until stop(body) says enough (or 10 s).
std::string read_events(const Served& s, const std::string& path, const std::function<bool(const std::string&)>& stop,
                        int* status = nullptr) {
  auto c = s.client();
  std::string body;
  const auto t0 = std::chrono::steady_clock::now();
  auto res = c.Get(path, [&](const char* d, std::size_t n) {
    body.append(d, n);
    return !stop(body) && std::chrono::steady_clock::now() - t0 < 10s;
  });
  if (status) *status = res ? res->status : -1;
  return body;
}

TEST(WebService, TheStreamStartsWithASnapshotAndPushesTheFit) {
  Served s;
  const SimulatedRun r = simulated_run(21);
  std::atomic<bool> connected{false};
  std::string body;
  std::thread reader([&] {
    body = read_events(s, "/events?bench=b1", [&](const std::string& b) {
      connected = b.find("event: snapshot") != std::string::npos;
      // Enough once both the fit's detail (with its curves) and a samples event are in, in
      // whichever order the service's pushes reach the page (a busy machine can order them
      // either way).
      const bool detail = b.find("\"curves\":{") != std::string::npos &&
                          b.find("\n\n", b.find("\"curves\":{")) != std::string::npos;
      return detail && b.find("event: samples") != std::string::npos;
    });
  });
  for (int i = 0; i < 500 && !connected; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_TRUE(connected);
  {
    std::lock_guard lock(s.service->mutex());
    feed_run(s.service->lab(), r);
  }
  s.service->flush(t0_us + 60 * sec_us);
  reader.join();
  EXPECT_EQ(body.rfind("retry: 2000\n\nevent: snapshot\n", 0), 0u);
  const auto at = body.find("event: detail\ndata: ");
  ASSERT_NE(at, std::string::npos);
  const Json d = Json::parse(body.substr(at + 20, body.find('\n', at + 20) - at - 20));
  EXPECT_EQ(d["run"]["fit"]["c4"]["value"].get<double>(), fit_param(r.fit, "combined", "c4"));
  EXPECT_NE(body.find("event: samples"), std::string::npos);
}

TEST(WebService, APagePastTheCapIsRefused) {
  WebServiceOptions o;
  o.fanout.max_clients = 1;
  Served s(o);
  std::atomic<bool> first_in{false}, release{false};
  std::thread holder([&] {
    read_events(s, "/events", [&](const std::string& b) {
      if (b.find("event: snapshot") != std::string::npos) first_in = true;
      return release.load();
    });
  });
  for (int i = 0; i < 500 && !first_in; ++i) std::this_thread::sleep_for(10ms);
  ASSERT_TRUE(first_in);
  int status = 0;
  const std::string refused = read_events(s, "/events", [](const std::string&) { return false; }, &status);
  EXPECT_EQ(status, 503);
  EXPECT_NE(refused.find("--max-clients"), std::string::npos) << refused;
  release = true;
  // The holder ends at its next event (a keep-alive at the latest): publish one now.
  s.service->lab().on_samples("b1", one_sample("b1", 0, 1000, 1.0), t0_us);
  s.service->flush(t0_us);
  holder.join();
  EXPECT_EQ(s.service->fanout().counters().refused, 1);
}

TEST(WebService, ARefusedOrBrokenMessageIsNeverShown) {
  WebServiceOptions o;
  o.check = [](std::string_view channel, const void*, std::int64_t, std::int64_t) -> std::optional<GateResult> {
    if (channel != "SPINDOWN.b1.FIT") return std::nullopt;
    GateResult r;
    r.verdict = GateVerdict::not_signed;
    r.text = std::string(channel) + ": not signed";
    return r;
  };
  WebService s(o);
  const SimulatedRun r = simulated_run(4);
  feed(s, "SPINDOWN.b1.SAMPLE", one_sample("b1", 0, 1000, 0.0), t0_us);
  feed(s, "SPINDOWN.b1.FIT", r.fit, t0_us);  // refused by the check
  const unsigned char junk[40] = {1, 2, 3};
  s.take("SPINDOWN.b2.FIT", junk, sizeof junk, t0_us);  // not a fit_t
  s.take("OTHER.CHANNEL", junk, sizeof junk, t0_us);    // not the suite's: ignored
  std::lock_guard lock(s.mutex());
  const Json st = s.lab().state_json(t0_us);
  ASSERT_EQ(st["benches"].size(), 1u);
  EXPECT_TRUE(st["benches"][0]["last_fit"].is_null());
  EXPECT_EQ(st["lab"]["refused_messages"], 1);
  EXPECT_NE(st["lab"]["last_refused"].get<std::string>().find("not signed"), std::string::npos);
  EXPECT_EQ(st["lab"]["bad_messages"], 1);
}

// DNS rebinding: a page elsewhere whose name resolves to this PC asks with its own Host. Only IP
// literals, localhost, this PC's name and --allow-host names are served; others get 421 and no
// data. A class opening the page at once finds room in the accept queue (not cpp-httplib's 5).
TEST(WebService, OnlyThisServersNamesAreServed) {
  EXPECT_TRUE(host_allowed("127.0.0.1:8080", {}));
  EXPECT_TRUE(host_allowed("10.44.0.5", {}));
  EXPECT_TRUE(host_allowed("[::1]:8080", {}));
  EXPECT_TRUE(host_allowed("LocalHost:8080", {}));
  EXPECT_TRUE(host_allowed("", {}));
  EXPECT_TRUE(host_allowed("lab-pc.school.example:8080", {"Lab-PC.school.example"}));
  EXPECT_FALSE(host_allowed("attacker.example", {}));
  EXPECT_FALSE(host_allowed("127.0.0.1.attacker.example:8080", {}));
  EXPECT_FALSE(host_allowed("localhost.attacker.example", {}));
  EXPECT_FALSE(host_allowed("[not-an-address]:80", {}));

  Served s;
  auto c = s.client();
  auto ok = c.Get("/api/state");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
  httplib::Headers evil{{"Host", "attacker.example:8080"}};
  for (const char* path : {"/", "/api/state", "/bench/b1"}) {
    auto refused = c.Get(path, evil);
    ASSERT_TRUE(refused) << path;
    EXPECT_EQ(refused->status, 421) << path;
    EXPECT_NE(refused->body.find("--allow-host attacker.example"), std::string::npos) << refused->body;
    EXPECT_EQ(refused->body.find("{"), std::string::npos) << "no data: " << refused->body;
  }
}

TEST(WebService, ListenAddresses) {
  std::string host, why;
  int port = 0;
  EXPECT_TRUE(parse_listen_address("0.0.0.0:8080", host, port));
  EXPECT_EQ(host, "0.0.0.0");
  EXPECT_EQ(port, 8080);
  EXPECT_TRUE(parse_listen_address("[::]:80", host, port));
  EXPECT_EQ(host, "::");
  EXPECT_TRUE(parse_listen_address("localhost:0", host, port));
  EXPECT_FALSE(parse_listen_address("8080", host, port, &why));
  EXPECT_NE(why.find("ADDR:PORT"), std::string::npos);
  EXPECT_FALSE(parse_listen_address("host:99999", host, port, &why));
  EXPECT_FALSE(parse_listen_address(":80", host, port, &why));
}

}  // namespace
}  // namespace spindown
