#pragma once
// Work on many inputs with several threads while the results come out in input order: each
// file's fit is independent, but a user (and a diff of two outputs) expects the order given.
// At most `window` results wait for an earlier one, so memory stays bounded however many
// files there are.
#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace spindown {

// The thread count for --jobs 0: every core the process may use.
inline unsigned default_jobs() { return std::max(1u, std::thread::hardware_concurrency()); }

// Calls produce(i) for i in [0, n) on up to `jobs` threads and consume(i, result) on the
// calling thread in order 0, 1, 2, … . produce must be safe to run concurrently; an exception
// from it is rethrown here after the workers stop.
//
// Handoffs are batched: the calling thread sleeps until `batch` results in a row are ready (or
// the last ones), and a worker wakes it only then, and wakes only after unlocking, so a small
// file costs well under one sleep and wake instead of three or four.
template <class Produce, class Consume>
void for_each_ordered(std::size_t n, unsigned jobs, Produce&& produce, Consume&& consume) {
  using Result = decltype(produce(std::size_t{0}));
  jobs = std::max(1u, jobs);
  if (jobs == 1 || n < 2) {
    for (std::size_t i = 0; i < n; ++i) consume(i, produce(i));
    return;
  }
  const std::size_t window = 4 * static_cast<std::size_t>(jobs);
  const std::size_t batch = window / 2;  // the workers keep going while a batch is consumed
  std::vector<std::optional<Result>> slots(window);
  std::mutex mu;
  std::condition_variable ready, room;
  std::size_t next = 0, consumed = 0;
  std::size_t wanted_through = 0;  // the consumer sleeps until slots [consumed, this] are filled
  bool consumer_asleep = false;
  std::size_t workers_waiting = 0;
  bool stop = false;
  std::exception_ptr error;

  // Under the lock: whether the results the sleeping consumer waits for are all there.
  auto wanted_ready = [&] {
    for (std::size_t k = consumed; k <= wanted_through; ++k)
      if (!slots[k % window]) return false;
    return true;
  };

  auto worker = [&] {
    for (;;) {
      std::size_t i;
      {
        std::unique_lock lock(mu);
        if (!(stop || next >= n || next < consumed + window)) {
          ++workers_waiting;
          room.wait(lock, [&] { return stop || next >= n || next < consumed + window; });
          --workers_waiting;
        }
        if (stop || next >= n) return;
        i = next++;
      }
      std::optional<Result> r;
      try {
        r.emplace(produce(i));
      } catch (...) {
        {
          std::lock_guard lock(mu);
          if (!error) error = std::current_exception();
          stop = true;
        }
        ready.notify_all();
        room.notify_all();
        return;
      }
      bool wake = false;
      {
        std::lock_guard lock(mu);
        slots[i % window] = std::move(r);
        wake = consumer_asleep && i <= wanted_through && wanted_ready();
        if (wake) consumer_asleep = false;
      }
      if (wake) ready.notify_one();
    }
  };
  std::vector<std::thread> threads;
  const unsigned count = static_cast<unsigned>(std::min<std::size_t>(jobs, n));
  threads.reserve(count);
  for (unsigned k = 0; k < count; ++k) threads.emplace_back(worker);

  for (std::size_t i = 0; i < n; ++i) {
    std::optional<Result> r;
    bool wake_workers = false;
    {
      std::unique_lock lock(mu);
      if (!stop && !slots[i % window]) {
        wanted_through = std::min(n - 1, i + batch - 1);
        consumer_asleep = true;
        ready.wait(lock, [&] { return stop || (!consumer_asleep && slots[i % window].has_value()); });
        consumer_asleep = false;
      }
      if (!slots[i % window]) break;  // a worker failed
      r = std::move(slots[i % window]);
      slots[i % window].reset();
      ++consumed;
      wake_workers = workers_waiting > 0;
    }
    if (wake_workers) room.notify_all();
    try {
      consume(i, std::move(*r));
    } catch (...) {
      {
        std::lock_guard lock(mu);
        if (!error) error = std::current_exception();
        stop = true;
      }
      room.notify_all();
      break;
    }
  }
  {
    std::lock_guard lock(mu);
    stop = true;
  }
  room.notify_all();
  for (auto& t : threads) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace spindown
