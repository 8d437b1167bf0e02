#include "spindown/web_service.hpp"

#include <fmt/format.h>

#include "spindown/clock.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/loop_watchdog.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/service_notifier.hpp"
#include "spindown/stop_signal.hpp"

namespace spindown {

namespace {

// Decodes data as Msg and hands it on; what does not decode is a bad message of the lab, named.
template <class Msg, class Feed>
void decode_and(WebLab& lab, std::string_view channel, const void* data, std::int64_t size, std::int64_t now,
                Feed feed) {
  thread_local Msg msg;  // decoding reuses its vectors' capacity
  std::string why;
  if (!decode_message(msg, data, size, &why)) {
    lab.on_bad_message(fmt::format("{}: {} bytes that do not decode as {}: {}", channel, size, Msg::getTypeName(), why),
                       now);
    return;
  }
  feed(msg);
}

}  // namespace

WebService::WebService(WebServiceOptions options)
    : opt_(std::move(options)), lab_(opt_.lab), fanout_(opt_.fanout) {}

WebService::~WebService() {
  if (server_) server_->stop();
}

void WebService::take(std::string_view channel, const void* data, std::int64_t size, std::int64_t now) {
  const auto parsed = parse_channel(channel);
  if (!parsed) return;  // not the suite's channel
  std::lock_guard lock(mutex_);
  if (opt_.check) {
    if (auto refused = opt_.check(channel, data, size, now)) {
      const bool sample = parsed->kind == ChannelKind::sample;
      lab_.on_refused(*refused, now, sample ? parsed->bench : std::string(), sample ? std::string() : parsed->bench);
      return;
    }
  }
  const std::string& id = parsed->bench;
  try {
    switch (parsed->kind) {
      case ChannelKind::sample:
        decode_and<samples_t>(lab_, channel, data, size, now, [&](const samples_t& m) { lab_.on_samples(id, m, now); });
        break;
      case ChannelKind::config:
        decode_and<config_t>(lab_, channel, data, size, now, [&](const config_t& m) { lab_.on_config(id, m, now); });
        break;
      case ChannelKind::status:
        decode_and<status_t>(lab_, channel, data, size, now, [&](const status_t& m) { lab_.on_status(id, m, now); });
        break;
      case ChannelKind::run:
        decode_and<run_t>(lab_, channel, data, size, now, [&](const run_t& m) { lab_.on_run(id, m, now); });
        break;
      case ChannelKind::fit:
        decode_and<fit_t>(lab_, channel, data, size, now, [&](const fit_t& m) { lab_.on_fit(id, m, now); });
        break;
      case ChannelKind::explain:
        decode_and<explain_t>(lab_, channel, data, size, now, [&](const explain_t& m) { lab_.on_explain(id, m, now); });
        break;
    }
  } catch (const std::exception& e) {
    lab_.on_bad_message(fmt::format("{}: {}", channel, e.what()), now);
  }
}

void WebService::flush(std::int64_t now_us) {
  std::lock_guard lock(mutex_);
  for (const WebUpdate& u : lab_.take_updates(now_us)) fanout_.publish(u);
}

bool WebService::start(std::string* why) {
  loop_ = std::make_unique<LcmLoop>(opt_.lcm_url);
  if (!loop_->good()) {
    if (why) *why = fmt::format("cannot start LCM{}{}", opt_.lcm_url.empty() ? "" : " at ", opt_.lcm_url);
    return false;
  }
  // Every message LCM reads reaches the lab (LCM 1.3.1's default queue of 30 drops in silence).
  const bool subscribed = loop_->subscribe_raw(
      "SPINDOWN\\..*", [this](const LcmMessage& m) { take(m.channel, m.data, m.size, m.recv_utime > 0 ? m.recv_utime : wall_us()); },
      {.queue_capacity = 0});
  if (!subscribed) {
    if (why) *why = "cannot subscribe to SPINDOWN\\..*";
    return false;
  }
  server_ = std::make_unique<WebServer>(lab_, mutex_, fanout_, opt_.server);
  return server_->bind(why);
}

std::string WebService::url() const {
  std::string host = server_ ? server_->bound_host() : opt_.server.host;
  if (host.find(':') != std::string::npos) host = "[" + host + "]";
  return fmt::format("http://{}:{}/", host, server_ ? server_->bound_port() : opt_.server.port);
}

int WebService::run(const StopSignals& stop) {
  server_->start();
  loop_->every(opt_.flush_period_s, [this](std::int64_t now) { flush(now); }, 0);
  ServiceNotifier notify;
  feed_watchdog_from_loop(*loop_, notify, [this](std::int64_t) { return server_->running(); });
  notify.ready(fmt::format("serving {} ", url()));
  const LcmLoopEnd end = loop_->run({.stop = &stop, .max_failures = -1});
  notify.stopping("stopping");
  loop_->unsubscribe_all();
  server_->stop();
  return end == LcmLoopEnd::failed ? 1 : 0;
}

}  // namespace spindown
