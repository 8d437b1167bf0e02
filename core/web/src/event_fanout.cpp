#include "spindown/event_fanout.hpp"

#include <algorithm>

namespace spindown {

EventFanout::EventFanout(EventFanoutOptions options) : opt_(options) {}

std::optional<EventFanout::ClientId> EventFanout::connect(std::string bench, std::string first) {
  auto c = std::make_shared<Client>();
  c->bench = std::move(bench);
  c->bytes = first.size();
  c->queue.push_back(std::make_shared<const std::string>(std::move(first)));
  std::lock_guard lock(mutex_);
  if (closed_ || clients_.size() >= opt_.max_clients) {
    ++counters_.refused;
    return std::nullopt;
  }
  const ClientId id = next_id_++;
  clients_.emplace(id, std::move(c));
  ++counters_.connected;
  counters_.clients = clients_.size();
  counters_.peak_clients = std::max(counters_.peak_clients, clients_.size());
  return id;
}

void EventFanout::disconnect(ClientId id) {
  std::shared_ptr<Client> c;
  {
    std::lock_guard lock(mutex_);
    auto it = clients_.find(id);
    if (it == clients_.end()) return;
    c = std::move(it->second);
    clients_.erase(it);
    counters_.clients = clients_.size();
  }
  std::lock_guard lock(c->mutex);
  c->closed = true;
  c->queue.clear();
  c->bytes = 0;
  c->wake.notify_all();
}

std::shared_ptr<EventFanout::Client> EventFanout::client(ClientId id) const {
  std::lock_guard lock(mutex_);
  auto it = clients_.find(id);
  return it == clients_.end() ? nullptr : it->second;
}

std::optional<std::string> EventFanout::bench_of(ClientId id) const {
  auto c = client(id);
  if (!c) return std::nullopt;
  return c->bench;
}

bool EventFanout::wants(const Client& c, const WebUpdate& u) {
  switch (u.to) {
    case WebUpdate::To::everyone: return true;
    case WebUpdate::To::room: return c.bench.empty();
    case WebUpdate::To::bench: return c.bench == u.bench;
    case WebUpdate::To::room_and_bench: return c.bench.empty() || c.bench == u.bench;
  }
  return false;
}

void EventFanout::publish(const WebUpdate& update) {
  if (!update.event) return;
  std::lock_guard lock(mutex_);
  for (auto& [id, c] : clients_) {
    if (!wants(*c, update)) continue;
    std::lock_guard client_lock(c->mutex);
    if (c->closed) continue;
    if (c->overflow) {  // already behind: its writer resyncs it; nothing more to keep
      ++counters_.dropped_events;
      continue;
    }
    if (c->queue.size() + 1 > opt_.max_queued_events || c->bytes + update.event->size() > opt_.max_queued_bytes) {
      counters_.dropped_events += static_cast<std::int64_t>(c->queue.size()) + 1;
      ++counters_.resyncs;
      c->queue.clear();
      c->bytes = 0;
      c->overflow = true;
    } else {
      c->queue.push_back(update.event);
      c->bytes += update.event->size();
      ++counters_.events_published;
    }
    c->wake.notify_one();
  }
}

EventFanout::Next EventFanout::next(ClientId id, std::string& out, std::chrono::milliseconds wait) {
  out.clear();
  auto c = client(id);
  if (!c) return Next::closed;
  std::unique_lock lock(c->mutex);
  c->wake.wait_for(lock, wait, [&] { return c->closed || c->overflow || !c->queue.empty(); });
  if (c->closed) return Next::closed;
  if (c->overflow) return Next::resync;
  if (c->queue.empty()) return Next::idle;
  std::deque<std::shared_ptr<const std::string>> batch;
  batch.swap(c->queue);
  c->bytes = 0;
  lock.unlock();
  std::size_t size = 0;
  for (const auto& e : batch) size += e->size();
  out.reserve(size);
  for (const auto& e : batch) out += *e;
  std::lock_guard counters_lock(mutex_);
  counters_.bytes_written += static_cast<std::int64_t>(size);
  return Next::events;
}

void EventFanout::resync(ClientId id, std::string snapshot) {
  auto c = client(id);
  if (!c) return;
  std::lock_guard lock(c->mutex);
  c->queue.clear();
  c->bytes = snapshot.size();
  c->queue.push_back(std::make_shared<const std::string>(std::move(snapshot)));
  c->overflow = false;
  c->wake.notify_one();
}

void EventFanout::close_all() {
  std::lock_guard lock(mutex_);
  closed_ = true;
  for (auto& [id, c] : clients_) {
    std::lock_guard client_lock(c->mutex);
    c->closed = true;
    c->wake.notify_all();
  }
}

EventFanoutCounters EventFanout::counters() const {
  std::lock_guard lock(mutex_);
  return counters_;
}

}  // namespace spindown
