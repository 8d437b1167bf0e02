#pragma once
// The live push of spindown-web: each connected page (a Server-Sent Events stream) has its own
// bounded queue of events. publish() only appends to the queues of the pages that want the event
// (never waits for a page), and each page's own HTTP thread writes its queue out. A page that
// falls behind (its queue past max_queued_events or max_queued_bytes: a slow or dead browser)
// loses what was queued and is resynced — its writer sends a fresh snapshot of the lab first —
// so one slow browser neither slows the service nor grows its memory. At most max_clients pages
// at once; the next one is refused (and counted).
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "spindown/web_lab.hpp"

namespace spindown {

struct EventFanoutOptions {
  std::size_t max_clients = 100;
  std::size_t max_queued_events = 1000;      // per client
  std::size_t max_queued_bytes = 16u << 20;  // per client
};

struct EventFanoutCounters {
  std::size_t clients = 0;        // connected now
  std::size_t peak_clients = 0;
  std::int64_t connected = 0;     // ever
  std::int64_t refused = 0;       // past max_clients
  std::int64_t resyncs = 0;       // queues that overflowed (events dropped, snapshot sent instead)
  std::int64_t dropped_events = 0;
  std::int64_t events_published = 0;  // events handed to some client's queue
  std::int64_t bytes_written = 0;     // handed to the writers
};

class EventFanout {
 public:
  using ClientId = std::uint64_t;
  enum class Next {
    events,  // out holds events to write
    resync,  // the queue overflowed: call resync() with a snapshot, then next() again
    idle,    // nothing within the wait (write a keep-alive comment)
    closed,  // the client or the fanout is closed: end the stream
  };

  explicit EventFanout(EventFanoutOptions options = {});

  // A new page: bench "" for the room page, else a bench page; first is queued first (the
  // snapshot). nullopt when max_clients pages are connected. Call it under the same lock as
  // publish() so that no event falls between the snapshot and the queue.
  std::optional<ClientId> connect(std::string bench, std::string first);
  void disconnect(ClientId id);

  // Queues the update for every page it is for. Never blocks on a page's writer.
  void publish(const WebUpdate& update);

  // The writer of page id: waits up to wait for something to write.
  Next next(ClientId id, std::string& out, std::chrono::milliseconds wait);
  // After Next::resync: the queue becomes snapshot alone (under publish()'s lock).
  void resync(ClientId id, std::string snapshot);
  // The bench a page follows ("" for the room page).
  std::optional<std::string> bench_of(ClientId id) const;

  // Every writer returns Next::closed, and connect() refuses from now on.
  void close_all();

  EventFanoutCounters counters() const;
  const EventFanoutOptions& options() const { return opt_; }

 private:
  struct Client {
    std::string bench;
    std::mutex mutex;
    std::condition_variable wake;
    std::deque<std::shared_ptr<const std::string>> queue;
    std::size_t bytes = 0;
    bool overflow = false;
    bool closed = false;
  };
  std::shared_ptr<Client> client(ClientId id) const;
  static bool wants(const Client& c, const WebUpdate& u);

  EventFanoutOptions opt_;
  mutable std::mutex mutex_;
  std::map<ClientId, std::shared_ptr<Client>> clients_;
  ClientId next_id_ = 1;
  bool closed_ = false;
  EventFanoutCounters counters_;
};

}  // namespace spindown
