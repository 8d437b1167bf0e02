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

LogRefit refit_log_session(const std::vector<std::string>& paths, const FitterOptions& options, bool keep_live_fits,
                           const std::function<void(const LcmLogEvent&)>& each_event, const RefitProgressFn& progress,
                           const RefitRunFn& each_run) {
  LogRefit out;
  out.file.file = paths.empty() ? std::string() : paths.front();
  out.session_files = paths;
  const std::string& path = out.file.file;
  RefitSink sink(out, path, each_run, !options.explain_base.empty());
  FitterCore core(options, sink);
  std::map<std::string, std::size_t, std::less<>> order;
  std::vector<char> channel_done;  // by session channel id: its bench's place is known
  // Each reader numbers its own channels; the core's numbering is the session's, by name.
  std::map<std::string, std::int32_t, std::less<>> session_ids;
  std::vector<std::uint64_t> fitter_sessions;  // of the fitters' heartbeats in the log (keep_live_fits)
  std::int64_t last_utime = 0, next_poll = std::numeric_limits<std::int64_t>::min();
  std::size_t file_problems = 0;
  std::int64_t events_read = 0, bytes_before = 0, bytes_total = 0;
  for (const auto& p : paths) {
    struct stat st {};
    if (::stat(p.c_str(), &st) == 0) bytes_total += st.st_size;
  }
  LcmLogEvent ev;
  std::size_t opened = 0;
  for (const std::string& file : paths) {
    // The core reads samples in place; a caller that sees each event may want the samples_t.
    LcmLogReader reader(file, each_event ? LcmSamples::view_and_message : LcmSamples::view_only);
    if (!reader.good()) {
      out.file.failures.push_back(reader.open_error());
      continue;
    }
    ++opened;
    std::vector<std::int32_t> id_map;  // reader's channel id -> the session's
    // Progress every 256 events, counted down (one test per event, none for a caller without one).
    constexpr std::size_t progress_every = 256;
    std::size_t until_progress = progress ? progress_every : std::numeric_limits<std::size_t>::max();
    while (reader.next(ev)) {
      if (each_event) each_event(ev);
      if (--until_progress == 0) {
        until_progress = progress_every;
        progress(bytes_before + ev.file_offset, std::max(bytes_total, bytes_before + reader.file_size()),
                 out.runs_fitted);
      }
      if (ev.number > 0) last_utime = ev.log_utime;
      // Host time passes as the log's events do: benches gone silent mid-coast are closed as live.
      if (ev.log_utime >= next_poll) {
        core.poll(ev.log_utime);
        next_poll = ev.log_utime + FitterCore::poll_period_us;
      }
      if (ev.channel_id >= 0) {
        const auto rid = static_cast<std::size_t>(ev.channel_id);
        if (rid >= id_map.size()) id_map.resize(rid + 1, -1);
        if (id_map[rid] < 0) {
          const auto [it, added] =
                session_ids.try_emplace(std::string(ev.channel), static_cast<std::int32_t>(session_ids.size()));
          id_map[rid] = it->second;
        }
        ev.channel_id = id_map[rid];
      }
      // A bench's first SAMPLE/CONFIG fixes its place; checked once per channel, not per event.
      const auto id = static_cast<std::size_t>(ev.channel_id);
      if (ev.channel_id < 0 || id >= channel_done.size() || !channel_done[id]) {
        if (!ev.bench.empty() && (ev.channel.ends_with(".SAMPLE") || ev.channel.ends_with(".CONFIG")) &&
            !order.contains(ev.bench)) {
          order.emplace(ev.bench, order.size());
          out.bench_order.emplace_back(ev.bench);
        }
        if (ev.channel_id >= 0) {
          if (id >= channel_done.size()) channel_done.resize(id + 1, 0);
          channel_done[id] = 1;
        }
      }
      switch (ev.kind) {
        // Decoded (and checked) once, by the reader: the core takes the message as it is, once its
        // gate let it through (the lab, and with a key its signature, as live).
        case LcmLogEvent::Kind::samples:
          if (core.admit_samples(ev.channel, ev.samples_view, ev.data, ev.data_size, ev.log_utime))
            core.on_samples(ev.channel_id, ev.bench, ev.samples_view, ev.log_utime);
          break;
        case LcmLogEvent::Kind::config:
          if (core.admit(ev.channel, ev.data, ev.data_size, ev.log_utime))
            core.on_config(ev.bench, ev.config, ev.log_utime);
          break;
        case LcmLogEvent::Kind::problem:
          if (ev.number > 0 && ev.data) {  // a message that does not decode: the core counts it
            core.on_message(ev.channel, ev.data, ev.data_size, ev.log_utime);
          } else if (++file_problems <= max_problems_listed) {
            out.file.diagnostics.push_back({Diagnostic::Severity::warning, file, ev.number, ev.problem});
          }
          break;
        case LcmLogEvent::Kind::other: {
          const auto parts = keep_live_fits ? split_channel(ev.channel) : std::nullopt;
          const auto kind = parts ? channel_kind(parts->suffix) : std::nullopt;
          if (kind == ChannelKind::status) {
            status_t st{};
            if (core.admit(ev.channel, ev.data, ev.data_size, ev.log_utime) &&
                decode_message(st, ev.data, ev.data_size) && st.service == "fitter" && st.source_session != 0 &&
                std::find(fitter_sessions.begin(), fitter_sessions.end(), std::uint64_t(st.source_session)) ==
                    fitter_sessions.end() &&
                fitter_sessions.size() < 1024)
              fitter_sessions.push_back(static_cast<std::uint64_t>(st.source_session));
            break;
          }
          // The live fitter's results as recorded (for --live and --compare): its own only when the
          // gate lets them through (the lab, and with a key their signature): a forged one is
          // counted and named, never compared.
          if ((kind == ChannelKind::fit || kind == ChannelKind::explain) &&
              core.admit(ev.channel, ev.data, ev.data_size, ev.log_utime)) {
            if (kind == ChannelKind::fit) keep_recorded(ev, file, out.live, "fit_t", out.file.diagnostics);
            else keep_recorded(ev, file, out.live_explains, "explain_t", out.file.diagnostics);
          }
          break;
        }
      }
    }
    events_read += reader.events_read();
    bytes_before += reader.file_size();
  }
  if (opened == 0) return out;
  core.finish(last_utime);
  out.counters = core.counters();
  // A FIT whose source is no fitter heard in the log is not a live result (a forged one): left out.
  if (!fitter_sessions.empty()) {
    std::erase_if(out.live, [&](const fit_t& m) {
      const auto session = static_cast<std::uint64_t>(m.source_session);
      if (session == 0 || std::find(fitter_sessions.begin(), fitter_sessions.end(), session) != fitter_sessions.end())
        return false;
      ++out.live_left_out;
      out.file.diagnostics.push_back(
          {Diagnostic::Severity::warning, path, 0,
           fmt::format("SPINDOWN.{}.FIT: run {} from {}: no fitter heard in this log has that session (a forged "
                       "FIT?); not taken as a live result",
                       shown_name(m.bench), m.run, source_text(m.source_host, session))});
      return true;
    });
  }
  const FitterCounters& c = out.counters;
  if (file_problems > max_problems_listed)
    out.file.diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                                    fmt::format("{} damaged parts of the file in all", file_problems)});
  if (sink.problems() > max_problems_listed)
    out.file.diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                                    fmt::format("{} unusable messages or samples in all (first {} listed)",
                                                sink.problems(), max_problems_listed)});
  if (sink.notes() > max_detector_notes)
    out.file.diagnostics.push_back({Diagnostic::Severity::note, path, 0,
                                    fmt::format("{} run detector notes in all (first {} listed)", sink.notes(),
                                                max_detector_notes)});
  out.file.diagnostics.push_back(
      {Diagnostic::Severity::note, path, 0,
       fmt::format("{} events: {} sample messages, {} config messages, {} samples used; {} decode errors, {} sequence "
                   "gaps ({} samples lost), {} repeated messages, {} NaN values, {} samples with time going back, "
                   "{} clock restarts",
                   events_read, c.sample_messages, c.config_messages, c.samples, c.decode_errors, c.seq_gaps,
                   c.samples_lost, c.duplicates, c.nan_values, c.time_backwards, c.clock_restarts)});

  // Runs in the order `spindown fit` lists them: by bench (first appearance), then number.
  auto rank = [&](const std::string& bench) {
    auto it = order.find(bench);
    return it == order.end() ? order.size() : it->second;
  };
  std::stable_sort(out.runs.begin(), out.runs.end(), [&](const RefitRun& a, const RefitRun& b) {
    const auto ra = rank(a.bench), rb = rank(b.bench);
    return ra != rb ? ra < rb : a.fit.run.number < b.fit.run.number;
  });
  out.file.samples = static_cast<std::size_t>(c.samples);
  out.file.lines_read = static_cast<std::size_t>(c.sample_messages);
  out.file.lines_skipped = static_cast<std::size_t>(c.decode_errors + c.duplicates + c.quantity_errors);
  const bool any_health = std::any_of(out.runs.begin(), out.runs.end(), [](const RefitRun& r) { return r.health.has_value(); });
  for (const RefitRun& r : out.runs) {
    out.file.runs.push_back(r.fit);
    if (any_health) out.file.health.push_back(r.health);
    if (r.fit.best.empty())
      out.file.failures.push_back(fmt::format("SPINDOWN.{}.SAMPLE: run {}: no model converged", r.bench,
                                              r.fit.run.number));
  }
  if (out.runs_fitted == 0)
    out.file.failures.push_back(c.samples > 0 ? fmt::format("no spin-down run found in {} samples", c.samples)
                                              : std::string("no samples on SPINDOWN.<bench>.SAMPLE channels"));
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
