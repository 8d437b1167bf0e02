#include "spindown/log_refit.hpp"

#include <algorithm>
#include <fmt/format.h>
#include <limits>
#include <map>
#include <string_view>
#include <vector>
#include <sys/stat.h>

#include "spindown/fit_message.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/session_id.hpp"

namespace spindown {

namespace {

constexpr std::size_t max_problems_listed = 20;  // per file, then counted

constexpr std::size_t max_detector_notes = 1000;  // per file, then counted (memory flat)

class RefitSink final : public FitterSink {
 public:
  // explains: the core explains each run (explain_ready follows fit_ready): a run is given out
  // with its EXPLAIN.
  RefitSink(LogRefit& out, const std::string& path, const RefitRunFn& each_run, bool explains)
      : out_(out), path_(path), each_run_(each_run), explains_(explains) {}
  void run_changed(const run_t&) override {}
  void fit_ready(const FitResult& r) override {
    ++out_.runs_fitted;
    if (!explains_) give(r);
  }
  void explain_ready(const FitResult& r) override { give(r); }
  void give(const FitResult& r) {
    if (!each_run_) {
      out_.runs.push_back({r.bench, r.fit, r.bench_source, r.first_seq, r.last_seq, r.health, r.explain});
      return;
    }
    if (r.fit.best.empty())
      out_.file.failures.push_back(fmt::format("SPINDOWN.{}.SAMPLE: run {}: no model converged", r.bench,
                                               r.fit.run.number));
    each_run_(RefitRun{r.bench, r.fit, r.bench_source, r.first_seq, r.last_seq, r.health, r.explain});
  }
  void problem(const std::string& text) override {
    if (++problems_ <= max_problems_listed)
      out_.file.diagnostics.push_back({Diagnostic::Severity::warning, path_, 0, text});
  }
  void diagnostic(const std::string&, const Diagnostic& d) override {
    if (++notes_ > max_detector_notes) return;
    Diagnostic copy = d;
    copy.source = path_ + " " + d.source;
    out_.file.diagnostics.push_back(std::move(copy));
  }
  std::size_t problems() const { return problems_; }
  std::size_t notes() const { return notes_; }

 private:
  LogRefit& out_;
  const std::string& path_;
  const RefitRunFn& each_run_;
  bool explains_ = false;
  std::size_t problems_ = 0, notes_ = 0;
};

// A recorded message of type T appended to kept, or a warning naming the event when it does not decode.
template <typename T>
void keep_recorded(const LcmLogEvent& ev, const std::string& file, std::vector<T>& kept, std::string_view type,
                   std::vector<Diagnostic>& diagnostics) {
  T m{};
  if (decode_message(m, ev.data, ev.data_size)) {
    kept.push_back(std::move(m));
    return;
  }
  diagnostics.push_back({Diagnostic::Severity::warning, file, ev.number,
                         fmt::format("event {} on {}: not a decodable {}; skipped", ev.number, ev.channel, type)});
}

}  // namespace

LogRefit refit_log(const std::string& path, const FitterOptions& options, bool keep_live_fits,
                   const std::function<void(const LcmLogEvent&)>& each_event, const RefitProgressFn& progress,
                   const RefitRunFn& each_run) {
  return refit_log_session({path}, options, keep_live_fits, each_event, progress, each_run);
}

namespace {

// The first and last event times of a log (0, 0 when it holds none).
std::pair<std::int64_t, std::int64_t> log_time_span(const std::string& path) {
  LcmLogReader reader(path, LcmSamples::view_only);
  std::int64_t first = 0, last = 0;
  LcmLogEvent ev;
  while (reader.good() && reader.next(ev)) {
    if (ev.number <= 0) continue;
    if (first == 0) first = ev.log_utime;
    last = ev.log_utime;
  }
  return {first, last};
}

}  // namespace

std::vector<std::vector<std::string>> log_sessions(const std::vector<std::string>& paths) {
  struct Span {
    std::string path;
    std::int64_t first, last;
  };
  std::vector<Span> spans;
  for (const auto& p : paths) {
    const auto [first, last] = log_time_span(p);
    spans.push_back({p, first, last});
  }
  // Unreadable or empty logs keep their place at the end, each alone.
  std::stable_sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) {
    if ((a.first == 0) != (b.first == 0)) return b.first == 0;
    return a.first < b.first;
  });
  std::vector<std::vector<std::string>> sessions;
  std::int64_t session_end = 0;
  for (const Span& sp : spans) {
    if (sp.first != 0 && !sessions.empty() && session_end != 0 && sp.first >= session_end) {
      sessions.back().push_back(sp.path);
    } else {
      sessions.push_back({sp.path});
    }
    session_end = sp.last;
  }
  return sessions;
}

namespace {

// A session's log files replayed through a FitterCore as the live fitter saw them: each event's
// channel numbered for the session, each bench's place fixed by its first SAMPLE/CONFIG, the core
// polled as the log's host time passes, the live fitter's own results kept for --live/--compare.
class SessionReplay {
 public:
  SessionReplay(LogRefit& out, const FitterOptions& options, bool keep_live_fits,
                const std::function<void(const LcmLogEvent&)>& each_event, const RefitProgressFn& progress,
                const RefitRunFn& each_run)
      : out_(out),
        keep_live_fits_(keep_live_fits),
        each_event_(each_event),
        progress_(progress),
        sink_(out, out.file.file, each_run, !options.explain_base.empty()),
        core_(options, sink_) {}

  void run(const std::vector<std::string>& paths) {
    for (const auto& p : paths) {
      struct stat st {};
      if (::stat(p.c_str(), &st) == 0) bytes_total_ += st.st_size;
    }
    std::size_t opened = 0;
    for (const std::string& file : paths) opened += replay_file(file);
    if (opened == 0) return;
    core_.finish(last_utime_);
    out_.counters = core_.counters();
    leave_out_forged_fits();
    summarize();
    order_runs();
  }

 private:
  bool replay_file(const std::string& file) {
    // The core reads samples in place; a caller that sees each event may want the samples_t.
    LcmLogReader reader(file, each_event_ ? LcmSamples::view_and_message : LcmSamples::view_only);
    if (!reader.good()) {
      out_.file.failures.push_back(reader.open_error());
      return false;
    }
    std::vector<std::int32_t> id_map;  // reader's channel id -> the session's
    // Progress every 256 events, counted down (one test per event, none for a caller without one).
    constexpr std::size_t progress_every = 256;
    std::size_t until_progress = progress_ ? progress_every : std::numeric_limits<std::size_t>::max();
    while (reader.next(ev_)) {
      if (each_event_) each_event_(ev_);
      if (--until_progress == 0) {
        until_progress = progress_every;
        progress_(bytes_before_ + ev_.file_offset, std::max(bytes_total_, bytes_before_ + reader.file_size()),
                  out_.runs_fitted);
      }
      if (ev_.number > 0) last_utime_ = ev_.log_utime;
      // Host time passes as the log's events do: benches gone silent mid-coast are closed as live.
      if (ev_.log_utime >= next_poll_) {
        core_.poll(ev_.log_utime);
        next_poll_ = ev_.log_utime + FitterCore::poll_period_us;
      }
      number_channel(id_map);
      place_bench();
      dispatch(file);
    }
    events_read_ += reader.events_read();
    bytes_before_ += reader.file_size();
    return true;
  }

  // Each reader numbers its own channels; the core's numbering is the session's, by name.
  void number_channel(std::vector<std::int32_t>& id_map) {
    if (ev_.channel_id < 0) return;
    const auto rid = static_cast<std::size_t>(ev_.channel_id);
    if (rid >= id_map.size()) id_map.resize(rid + 1, -1);
    if (id_map[rid] < 0) {
      const auto [it, added] =
          session_ids_.try_emplace(std::string(ev_.channel), static_cast<std::int32_t>(session_ids_.size()));
      id_map[rid] = it->second;
    }
    ev_.channel_id = id_map[rid];
  }

  // A bench's first SAMPLE/CONFIG fixes its place; checked once per channel, not per event.
  void place_bench() {
    const auto id = static_cast<std::size_t>(ev_.channel_id);
    if (ev_.channel_id >= 0 && id < channel_done_.size() && channel_done_[id]) return;
    if (!ev_.bench.empty() && (ev_.channel.ends_with(".SAMPLE") || ev_.channel.ends_with(".CONFIG")) &&
        !order_.contains(ev_.bench)) {
      order_.emplace(ev_.bench, order_.size());
      out_.bench_order.emplace_back(ev_.bench);
    }
    if (ev_.channel_id >= 0) {
      if (id >= channel_done_.size()) channel_done_.resize(id + 1, 0);
      channel_done_[id] = 1;
    }
  }

  void dispatch(const std::string& file) {
    switch (ev_.kind) {
      // Decoded (and checked) once, by the reader: the core takes the message as it is, once its
      // gate let it through (the lab, and with a key its signature, as live).
      case LcmLogEvent::Kind::samples:
        if (core_.admit_samples(ev_.channel, ev_.samples_view, ev_.data, ev_.data_size, ev_.log_utime))
          core_.on_samples(ev_.channel_id, ev_.bench, ev_.samples_view, ev_.log_utime);
        break;
      case LcmLogEvent::Kind::config:
        if (core_.admit(ev_.channel, ev_.data, ev_.data_size, ev_.log_utime))
          core_.on_config(ev_.bench, ev_.config, ev_.log_utime);
        break;
      case LcmLogEvent::Kind::problem:
        if (ev_.number > 0 && ev_.data) {  // a message that does not decode: the core counts it
          core_.on_message(ev_.channel, ev_.data, ev_.data_size, ev_.log_utime);
        } else if (++file_problems_ <= max_problems_listed) {
          out_.file.diagnostics.push_back({Diagnostic::Severity::warning, file, ev_.number, ev_.problem});
        }
        break;
      case LcmLogEvent::Kind::other: keep_live_result(file); break;
    }
  }

  // The fitters heard (their heartbeats), and the live fitter's results as recorded (for --live and
  // --compare): its own only when the gate lets them through (the lab, and with a key their
  // signature): a forged one is counted and named, never compared.
  void keep_live_result(const std::string& file) {
    const auto parts = keep_live_fits_ ? split_channel(ev_.channel) : std::nullopt;
    const auto kind = parts ? channel_kind(parts->suffix) : std::nullopt;
    if (kind == ChannelKind::status) {
      status_t st{};
      if (core_.admit(ev_.channel, ev_.data, ev_.data_size, ev_.log_utime) &&
          decode_message(st, ev_.data, ev_.data_size) && st.service == "fitter" && st.source_session != 0 &&
          std::find(fitter_sessions_.begin(), fitter_sessions_.end(), std::uint64_t(st.source_session)) ==
              fitter_sessions_.end() &&
          fitter_sessions_.size() < 1024)
        fitter_sessions_.push_back(static_cast<std::uint64_t>(st.source_session));
      return;
    }
    if ((kind == ChannelKind::fit || kind == ChannelKind::explain) &&
        core_.admit(ev_.channel, ev_.data, ev_.data_size, ev_.log_utime)) {
      if (kind == ChannelKind::fit) keep_recorded(ev_, file, out_.live, "fit_t", out_.file.diagnostics);
      else keep_recorded(ev_, file, out_.live_explains, "explain_t", out_.file.diagnostics);
    }
  }

  // A FIT whose source is no fitter heard in the log is not a live result (a forged one): left out.
  void leave_out_forged_fits() {
    if (fitter_sessions_.empty()) return;
    const std::string& path = out_.file.file;
    std::erase_if(out_.live, [&](const fit_t& m) {
      const auto session = static_cast<std::uint64_t>(m.source_session);
      if (session == 0 || std::find(fitter_sessions_.begin(), fitter_sessions_.end(), session) != fitter_sessions_.end())
        return false;
      ++out_.live_left_out;
      out_.file.diagnostics.push_back(
          {Diagnostic::Severity::warning, path, 0,
           fmt::format("SPINDOWN.{}.FIT: run {} from {}: no fitter heard in this log has that session (a forged "
                       "FIT?); not taken as a live result",
                       shown_name(m.bench), m.run, source_text(m.source_host, session))});
      return true;
    });
  }

  void summarize() {
    const std::string& path = out_.file.file;
    const FitterCounters& c = out_.counters;
    auto& diagnostics = out_.file.diagnostics;
    if (file_problems_ > max_problems_listed)
      diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                             fmt::format("{} damaged parts of the file in all", file_problems_)});
    if (sink_.problems() > max_problems_listed)
      diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                             fmt::format("{} unusable messages or samples in all (first {} listed)", sink_.problems(),
                                         max_problems_listed)});
    if (sink_.notes() > max_detector_notes)
      diagnostics.push_back({Diagnostic::Severity::note, path, 0,
                             fmt::format("{} run detector notes in all (first {} listed)", sink_.notes(),
                                         max_detector_notes)});
    diagnostics.push_back(
        {Diagnostic::Severity::note, path, 0,
         fmt::format("{} events: {} sample messages, {} config messages, {} samples used; {} decode errors, {} "
                     "sequence gaps ({} samples lost), {} repeated messages, {} NaN values, {} samples with time "
                     "going back, {} clock restarts",
                     events_read_, c.sample_messages, c.config_messages, c.samples, c.decode_errors, c.seq_gaps,
                     c.samples_lost, c.duplicates, c.nan_values, c.time_backwards, c.clock_restarts)});
  }

  // Runs in the order `spindown fit` lists them: by bench (first appearance), then number.
  void order_runs() {
    const FitterCounters& c = out_.counters;
    auto rank = [&](const std::string& bench) {
      auto it = order_.find(bench);
      return it == order_.end() ? order_.size() : it->second;
    };
    std::stable_sort(out_.runs.begin(), out_.runs.end(), [&](const RefitRun& a, const RefitRun& b) {
      const auto ra = rank(a.bench), rb = rank(b.bench);
      return ra != rb ? ra < rb : a.fit.run.number < b.fit.run.number;
    });
    out_.file.samples = static_cast<std::size_t>(c.samples);
    out_.file.lines_read = static_cast<std::size_t>(c.sample_messages);
    out_.file.lines_skipped = static_cast<std::size_t>(c.decode_errors + c.duplicates + c.quantity_errors);
    const bool any_health =
        std::any_of(out_.runs.begin(), out_.runs.end(), [](const RefitRun& r) { return r.health.has_value(); });
    for (const RefitRun& r : out_.runs) {
      out_.file.runs.push_back(r.fit);
      if (any_health) out_.file.health.push_back(r.health);
      if (r.fit.best.empty())
        out_.file.failures.push_back(fmt::format("SPINDOWN.{}.SAMPLE: run {}: no model converged", r.bench,
                                                 r.fit.run.number));
    }
    if (out_.runs_fitted == 0)
      out_.file.failures.push_back(c.samples > 0 ? fmt::format("no spin-down run found in {} samples", c.samples)
                                                 : std::string("no samples on SPINDOWN.<bench>.SAMPLE channels"));
  }

  LogRefit& out_;
  const bool keep_live_fits_;
  const std::function<void(const LcmLogEvent&)>& each_event_;
  const RefitProgressFn& progress_;
  RefitSink sink_;
  FitterCore core_;
  LcmLogEvent ev_;
  std::map<std::string, std::size_t, std::less<>> order_;
  std::vector<char> channel_done_;  // by session channel id: its bench's place is known
  std::map<std::string, std::int32_t, std::less<>> session_ids_;
  std::vector<std::uint64_t> fitter_sessions_;  // of the fitters' heartbeats in the log (keep_live_fits)
  std::int64_t last_utime_ = 0, next_poll_ = std::numeric_limits<std::int64_t>::min();
  std::size_t file_problems_ = 0;
  std::int64_t events_read_ = 0, bytes_before_ = 0, bytes_total_ = 0;
};

}  // namespace

LogRefit refit_log_session(const std::vector<std::string>& paths, const FitterOptions& options, bool keep_live_fits,
                           const std::function<void(const LcmLogEvent&)>& each_event, const RefitProgressFn& progress,
                           const RefitRunFn& each_run) {
  LogRefit out;
  out.file.file = paths.empty() ? std::string() : paths.front();
  out.session_files = paths;
  SessionReplay(out, options, keep_live_fits, each_event, progress, each_run).run(paths);
  return out;
}

Json refit_file_json(const LogRefit& refit, const ReportOptions& opt) {
  Json j = file_fit_json(refit.file, opt);
  if (refit.session_files.size() > 1) j["session_files"] = refit.session_files;
  Json& runs = j["runs"];
  for (std::size_t i = 0; i < refit.runs.size() && i < runs.size(); ++i)
    tag_run_json(runs[i], {refit.runs[i].bench, refit.runs[i].first_seq, refit.runs[i].last_seq});
  return j;
}

}  // namespace spindown
