#pragma once
// FitterCore's state per bench, shared by its files (fitter_core.cpp: taking messages and
// samples; fitter_runs.cpp: the detector's events -> RUN and FIT; fitter_status.cpp: options
// and STATUS). Private to the pipeline module.
#include <cstdint>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "spindown/fitter_core.hpp"
#include "spindown/sample_stream.hpp"

namespace spindown {

struct FitterCore::Bench {
  struct Sample {
    double t_s;
    double value;
    std::int64_t seq;
  };
  // The detector's buffer again, with sequence numbers, oldest first: a ring that grows to the
  // largest buffer seen (at most RunOptions::max_buffer + 1) and allocates no more after that.
  class Mirror {
   public:
    std::size_t size() const { return count_; }
    const Sample& operator[](std::size_t i) const { return slots_[(head_ + i) & mask_]; }
    void push_back(const Sample& s) {
      if (count_ == slots_.size()) grow();
      slots_[(head_ + count_) & mask_] = s;
      ++count_;
    }
    void drop_front(std::size_t n) {
      head_ = (head_ + n) & mask_;
      count_ -= n;
    }

   private:
    void grow() {
      std::vector<Sample> bigger(std::max<std::size_t>(256, 2 * slots_.size()));
      for (std::size_t i = 0; i < count_; ++i) bigger[i] = (*this)[i];
      slots_.swap(bigger);
      head_ = 0;
      mask_ = slots_.size() - 1;
    }
    std::vector<Sample> slots_;  // size a power of two
    std::size_t head_ = 0, count_ = 0, mask_ = 0;
  };
  Bench(std::string bench_id, const RunOptions& runs, const SampleStreamOptions& stream_options)
      : id(std::move(bench_id)), channel(fmt::format("SPINDOWN.{}.SAMPLE", id)), detector(runs, channel) {
    stream.options = stream_options;
  }

  std::string id;
  std::string channel;
  RunDetector detector;
  Mirror mirror;  // samples of a run, with the sequence numbers a published run names
  // The lowest reading the bench has given (explain: a sensor that reads zero at rest cannot hide a
  // negative offset), as spindown explain takes it from the whole recording.
  double lowest_reading = std::numeric_limits<double>::infinity();
  std::uint64_t last_active = 0, arrival = 0;
  std::int64_t last_sample_utime = 0;  // host time of its last samples (poll(): silent benches)
  bool sampled = false;                 // a sample was taken (the first one's seq: joined_stream())
  std::int64_t last_refused_utime = 0;  // host time its SAMPLE channel last brought a refused message
  std::string last_refused;             // and why (the gate's words)
  bool refused_said = false;            // "kept open: … refused" said for this silence

  std::optional<BenchParams> config;  // from the CONFIG of the stream's source
  std::string config_problem;
  // The latest CONFIG of other sources on the channel (a restarted bridge announces itself before
  // its samples take over; a second source's is never used): applied when that source takes over.
  struct OtherConfig {
    std::uint64_t session = 0;
    std::string host;
    std::optional<BenchParams> params;
    std::string problem;
  };
  std::vector<OtherConfig> other_configs;  // at most 4

  SampleStream stream;  // the log reader's checks too (sample_stream.hpp), so refit == fit
  bool pending_restart = false;  // the clock restarted: tell the detector before the next sample
  std::string pending_new_source;  // not empty: the restart is a new source taking over, in these words

  // Rate cap (token bucket on host receive time).
  double tokens = 0;
  std::int64_t tokens_utime = 0;
  bool bucket_started = false;

  // The open run as last published: 0 none, 1 coasting, 2 stopped (provisional).
  int open_state = 0;
  Run open_run;
  std::string run_host;            // the source of the open (or last) run's samples
  std::uint64_t run_session = 0;

  std::size_t base() const { return detector.samples_seen() - mirror.size(); }
  const Sample* at(std::size_t index) const {
    const std::size_t b = base();
    return index >= b && index - b < mirror.size() ? &mirror[index - b] : nullptr;
  }
};

inline void FitterCore::trim_mirror(Bench& b) {
  const std::size_t keep = b.detector.buffered();
  if (b.mirror.size() > keep) b.mirror.drop_front(b.mirror.size() - keep);
}

}  // namespace spindown
