// spindown-log-summary: reads LCM event logs in the order of their first event's time (rotated
// files of one session continue each other; a name suffix .1, .2 does not sort by time) and prints one JSON object: events per file and channel, problems (a
// truncated tail, garbage), per bench the SAMPLE sequence (messages, gaps, missing samples,
// repeats, last publish time) and the last status event of spindown-logger in each file.
// Exit code 0 when every file opened, 1 otherwise.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdint>
#include <fmt/format.h>
#include <map>
#include <nlohmann/json.hpp>

#include <spindown/status_t.hpp>

#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_log_reader.hpp"

namespace {

struct BenchSeq {
  std::int64_t messages = 0, samples = 0, gaps = 0, missing = 0, repeats = 0;
  std::int64_t first_seq = -1, next_seq = 0, last_utime = 0, last_log_utime = 0;
};

nlohmann::json status_json(const spindown::status_t& s) {
  nlohmann::json j{{"service", s.service}, {"instance", s.instance}, {"state", s.state}, {"utime", s.utime},
                   {"last_error", s.last_error}};
  for (std::size_t i = 0; i < s.counter_name.size() && i < s.counter_value.size(); ++i)
    j["counters"][s.counter_name[i]] = s.counter_value[i];
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-log-summary: what is in LCM event logs, as JSON"};
  std::vector<std::string> files;
  app.add_option("FILE", files, "LCM logs, in order")->required();
  CLI11_PARSE(app, argc, argv);
  {
    std::vector<std::pair<std::int64_t, std::string>> by_time;
    spindown::LcmLogEvent first;
    for (const auto& path : files) {
      spindown::LcmLogReader reader(path);
      std::int64_t t = INT64_MAX;
      while (reader.good() && reader.next(first))
        if (first.kind != spindown::LcmLogEvent::Kind::problem) {
          t = first.log_utime;
          break;
        }
      by_time.emplace_back(t, path);
    }
    std::stable_sort(by_time.begin(), by_time.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    files.clear();
    for (auto& [t, path] : by_time) files.push_back(path);
  }

  nlohmann::json out;
  out["files"] = nlohmann::json::array();
  std::map<std::string, BenchSeq> benches;
  std::int64_t total_events = 0, total_problems = 0, sample_messages = 0;
  int rc = 0;
  spindown::LcmLogEvent ev;
  for (const auto& path : files) {
    spindown::LcmLogReader reader(path);
    nlohmann::json f{{"file", path}};
    if (!reader.good()) {
      f["error"] = reader.open_error();
      out["files"].push_back(f);
      rc = 1;
      continue;
    }
    std::map<std::string, std::int64_t> channels;
    nlohmann::json problems = nlohmann::json::array();
    nlohmann::json first_status, last_status;
    std::int64_t events = 0, nproblems = 0, statuses = 0;
    while (reader.next(ev)) {
      if (ev.kind == spindown::LcmLogEvent::Kind::problem) {
        ++nproblems;
        if (problems.size() < 10) problems.push_back(ev.problem);
        continue;
      }
      ++events;
      ++channels[std::string(ev.channel)];
      if (ev.kind == spindown::LcmLogEvent::Kind::samples) {
        BenchSeq& b = benches[std::string(ev.bench)];
        const auto& s = ev.samples;
        if (b.messages > 0) {
          if (s.seq > b.next_seq) {
            ++b.gaps;
            b.missing += s.seq - b.next_seq;
          } else if (s.seq < b.next_seq) {
            ++b.repeats;
          }
        } else {
          b.first_seq = s.seq;
        }
        b.next_seq = s.seq + s.n;
        ++b.messages;
        b.samples += s.n;
        b.last_utime = s.utime;
        b.last_log_utime = ev.log_utime;
        ++sample_messages;
      } else if (ev.kind == spindown::LcmLogEvent::Kind::other && ev.data) {
        const auto parsed = spindown::parse_channel(ev.channel);
        if (parsed && parsed->kind == spindown::ChannelKind::status) {
          spindown::status_t st{};
          if (st.decode(ev.data, 0, ev.data_size) >= 0 && st.service == "logger" && st.pid > 0) {
            // Only the logger's own events written into this file (its heartbeats have other states too).
            ++statuses;
            if (first_status.is_null()) first_status = status_json(st);
            last_status = status_json(st);
          }
        }
      }
    }
    f["events"] = events;
    f["channels"] = channels;
    f["problems"] = nproblems;
    f["problem_texts"] = problems;
    f["logger_status_events"] = statuses;
    f["first_logger_status"] = first_status;
    f["last_logger_status"] = last_status;
    out["files"].push_back(f);
    total_events += events;
    total_problems += nproblems;
  }
  for (const auto& [name, b] : benches)
    out["benches"][name] = {{"messages", b.messages}, {"samples", b.samples},   {"first_seq", b.first_seq},
                            {"next_seq", b.next_seq}, {"gaps", b.gaps},         {"missing", b.missing},
                            {"repeats", b.repeats},   {"last_utime", b.last_utime}, {"last_log_utime", b.last_log_utime}};
  out["events"] = total_events;
  out["problems"] = total_problems;
  out["sample_messages"] = sample_messages;
  fmt::print("{}\n", out.dump());
  return rc;
}
