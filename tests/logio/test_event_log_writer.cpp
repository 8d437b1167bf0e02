// EventLogWriter, LogRecorder and StatusHeartbeat: the logs they write are standard LCM logs
// (read back with lcm::LogFile and LcmLogReader), rotation never splits an event, only flushed
// events are on disk, write errors are counted with the path and errno text, and the logger's
// own status events in the log carry the counters.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <regex>
#include <sched.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <thread>
#include <unistd.h>

#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/event_log_writer.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/log_recorder.hpp"

namespace fs = std::filesystem;
using namespace spindown;

namespace {

constexpr std::int64_t kT0 = 1795300000000000;  // µs, a fixed "now"

class TempDir {
 public:
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "spindown-logtest-XXXXXX").string();
    path_ = mkdtemp(tmpl.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

struct ReadEvent {
  std::int64_t utime;
  std::string channel;
  std::string data;
};

std::vector<ReadEvent> read_with_logfile(const std::string& path) {
  std::vector<ReadEvent> out;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  if (!log.good()) return out;
  for (int i = 0; i < 1000000; ++i) {
    const lcm::LogEvent* ev = log.readNextEvent();
    if (!ev) break;
    out.push_back({ev->timestamp, ev->channel, std::string(static_cast<const char*>(ev->data), ev->datalen)});
  }
  return out;
}

std::int64_t problems_in(const std::string& path) {
  LcmLogReader reader(path);
  EXPECT_TRUE(reader.good()) << reader.open_error();
  LcmLogEvent ev;
  std::int64_t problems = 0;
  for (int i = 0; i < 1000000 && reader.next(ev); ++i)
    if (ev.kind == LcmLogEvent::Kind::problem) ++problems;
  return problems;
}

std::vector<ReadEvent> data_events(const std::vector<ReadEvent>& all, const std::string& status_channel) {
  std::vector<ReadEvent> out;
  for (const auto& e : all)
    if (e.channel != status_channel) out.push_back(e);
  return out;
}

std::vector<status_t> status_events(const std::vector<ReadEvent>& all, const std::string& status_channel) {
  std::vector<status_t> out;
  for (const auto& e : all)
    if (e.channel == status_channel) {
      status_t st{};
      EXPECT_GE(st.decode(e.data.data(), 0, static_cast<int>(e.data.size())), 0);
      out.push_back(st);
    }
  return out;
}

std::string payload(int i, std::size_t size = 100) {
  std::string s(size, 'x');
  const std::string tag = std::to_string(i);
  s.replace(0, tag.size(), tag);
  return s;
}

std::string encode_samples(const std::string& bench, std::int64_t seq, int n) {
  samples_t s{};  // every field zero (lcm-gen types leave them uninitialised)
  s.utime = kT0;
  s.bench = bench;
  s.seq = seq;
  s.n = n;
  s.device_time_us.assign(n, 0);
  s.host_time_us.assign(n, 0);
  s.value.assign(n, 1.0);
  s.raw_adc.assign(n, -1);
  std::string buf(static_cast<std::size_t>(s.getEncodedSize()), '\0');
  s.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

EventLogWriterOptions options_in(const TempDir& dir) {
  EventLogWriterOptions o;
  o.dir = dir.path();
  o.bench = "b1";
  return o;
}

}  // namespace

TEST(EventLogFileName, DateTimeBenchAndSuffix) {
  const std::string name = event_log_file_name("spindown", "bench-3", 1795300000);
  EXPECT_TRUE(std::regex_match(name, std::regex(R"(spindown-\d{4}-\d{2}-\d{2}-\d{6}-bench-3\.lcm)"))) << name;
  EXPECT_TRUE(std::regex_match(event_log_file_name("lab", "", 1795300000, 2),
                               std::regex(R"(lab-\d{4}-\d{2}-\d{2}-\d{6}\.2\.lcm)")));
}

TEST(EventLogWriterOptions, RejectsBadValues) {
  std::string why;
  EventLogWriterOptions o;
  o.bench = "no spaces";
  EXPECT_FALSE(o.is_valid(&why));
  o = {};
  o.prefix = "a/b";
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_NE(why.find("a/b"), std::string::npos);
  o = {};
  o.rotate_size_mb = -1;
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_THROW(EventLogWriter(o, kT0), std::invalid_argument);
}

TEST(EventLogWriter, WritesAStandardLogThatLcmLogFileReads) {
  TempDir dir;
  const auto o = options_in(dir);
  std::string path;
  {
    EventLogWriter w(o, kT0);
    w.open(kT0);
    path = w.current_path();
    for (int i = 0; i < 50; ++i)
      ASSERT_TRUE(w.write(kT0 + i * 1000, i % 2 ? "SPINDOWN.b1.FIT" : "OTHER", payload(i).data(), 100, kT0 + i));
    w.close(kT0 + 100000, "stopped");
    EXPECT_EQ(w.counters().events, 50);
    EXPECT_EQ(w.counters().files, 1);
    EXPECT_EQ(w.counters().write_errors, 0);
  }
  const auto all = read_with_logfile(path);
  const auto data = data_events(all, o.status_channel);
  ASSERT_EQ(data.size(), 50u);
  for (int i = 0; i < 50; ++i) {
    EXPECT_EQ(data[i].utime, kT0 + i * 1000);
    EXPECT_EQ(data[i].channel, i % 2 ? "SPINDOWN.b1.FIT" : "OTHER");
    EXPECT_EQ(data[i].data, payload(i));
  }
  // The log describes itself: a status event opens and closes it, the last one with the counts.
  const auto st = status_events(all, o.status_channel);
  ASSERT_EQ(st.size(), 2u);
  EXPECT_EQ(st.front().state, "opened");
  EXPECT_EQ(st.back().state, "stopped");
  EXPECT_EQ(st.back().service, "logger");
  EXPECT_EQ(st.back().instance, "b1");
  EXPECT_EQ(find_counter(st.back(), "events"), 50);
  EXPECT_EQ(find_counter(st.back(), "write_errors"), 0);
  EXPECT_EQ(problems_in(path), 0);
}

TEST(EventLogWriter, NeverOverwritesAnExistingLog) {
  TempDir dir;
  const auto o = options_in(dir);
  EventLogWriter a(o, kT0), b(o, kT0);
  a.open(kT0);
  b.open(kT0);  // same second, same name: b gets a suffix
  EXPECT_NE(a.current_path(), b.current_path());
  EXPECT_NE(b.current_path().find(".1.lcm"), std::string::npos) << b.current_path();
}

TEST(EventLogWriter, RotatesBySizeBetweenEventsAndLosesNothing) {
  TempDir dir;
  auto o = options_in(dir);
  o.rotate_size_mb = 0.01;  // 10 kB
  std::vector<std::string> files;
  {
    EventLogWriter w(o, kT0);
    w.open(kT0);
    for (int i = 0; i < 400; ++i) ASSERT_TRUE(w.write(kT0 + i, "CH", payload(i).data(), 100, kT0 + i));
    w.close(kT0 + 1000);
    files = w.files();
  }
  ASSERT_GE(files.size(), 4u);  // 400 × 130 bytes ≈ 52 kB
  int next = 0;
  for (const auto& f : files) {
    EXPECT_LE(fs::file_size(f), 10000u + 1000u) << f;  // the limit plus the closing status event
    EXPECT_EQ(problems_in(f), 0) << f;
    const auto all = read_with_logfile(f);
    const auto st = status_events(all, o.status_channel);
    ASSERT_EQ(st.size(), 2u) << f;
    EXPECT_EQ(st.front().state, "opened");
    EXPECT_EQ(st.back().state, f == files.back() ? "stopped" : "rotating");
    for (const auto& e : data_events(all, o.status_channel)) EXPECT_EQ(e.data, payload(next++));
  }
  EXPECT_EQ(next, 400);
}

TEST(EventLogWriter, RotatesByTimeOnlyWhenTheFileHasEvents) {
  TempDir dir;
  auto o = options_in(dir);
  o.rotate_time_s = 10;
  EventLogWriter w(o, kT0);
  w.open(kT0);
  w.tick(kT0 + 30'000'000);  // no events yet: no empty files
  EXPECT_EQ(w.counters().files, 1);
  ASSERT_TRUE(w.write(kT0, "CH", "a", 1, kT0 + 30'000'000));
  w.tick(kT0 + 30'500'000);
  EXPECT_EQ(w.counters().files, 2);
  ASSERT_TRUE(w.write(kT0, "CH", "b", 1, kT0 + 31'000'000));
  w.tick(kT0 + 35'000'000);
  EXPECT_EQ(w.counters().files, 2);
  w.tick(kT0 + 41'000'000);
  EXPECT_EQ(w.counters().files, 3);
}

TEST(EventLogWriter, OnlyFlushedEventsAreOnDiskAndTheFileEndsOnAnEvent) {
  TempDir dir;
  const auto o = options_in(dir);
  EventLogWriter w(o, kT0);
  w.open(kT0);
  for (int i = 0; i < 30; ++i) ASSERT_TRUE(w.write(kT0 + i, "CH", payload(i).data(), 100, kT0 + i));
  EXPECT_TRUE(w.has_unflushed());
  EXPECT_EQ(fs::file_size(w.current_path()), 0u);  // still in the buffer
  ASSERT_TRUE(w.flush(kT0 + 100));
  EXPECT_FALSE(w.has_unflushed());
  for (int i = 30; i < 50; ++i) ASSERT_TRUE(w.write(kT0 + i, "CH", payload(i).data(), 100, kT0 + i));
  // What a SIGKILL now would leave: the file as the kernel has it.
  const auto snapshot = dir.path() + "/snapshot.lcm";
  fs::copy_file(w.current_path(), snapshot);
  EXPECT_EQ(problems_in(snapshot), 0);
  EXPECT_EQ(data_events(read_with_logfile(snapshot), o.status_channel).size(), 30u);
  EXPECT_EQ(w.counters().flushes, 1);
}

TEST(EventLogWriter, ABufferFullGoesToTheKernelInWholeEvents) {
  TempDir dir;
  auto o = options_in(dir);
  o.buffer_bytes = 4096;
  EventLogWriter w(o, kT0);
  w.open(kT0);
  for (int i = 0; i < 200; ++i) ASSERT_TRUE(w.write(kT0 + i, "CH", payload(i, 333).data(), 333, kT0 + i));
  const auto snapshot = dir.path() + "/snapshot.lcm";
  fs::copy_file(w.current_path(), snapshot);
  EXPECT_GT(fs::file_size(snapshot), 0u);
  EXPECT_EQ(problems_in(snapshot), 0);  // no half event at the end
  EXPECT_GT(data_events(read_with_logfile(snapshot), o.status_channel).size(), 150u);
}

TEST(EventLogWriter, MissingDirectoryIsAClearError) {
  EventLogWriterOptions o;
  o.dir = "/nonexistent/spindown-logs";
  EventLogWriter w(o, kT0);
  try {
    w.open(kT0);
    FAIL() << "no error";
  } catch (const EventLogError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/nonexistent/spindown-logs/spindown-"), std::string::npos) << what;
    EXPECT_NE(what.find("No such file or directory"), std::string::npos) << what;
  }
}

TEST(EventLogWriter, WriteErrorsAreCountedWithPathAndErrnoAndLoggingResumes) {
  TempDir dir;
  auto o = options_in(dir);
  o.buffer_bytes = 4096;
  o.reopen_interval_s = 1.0;
  EventLogWriter w(o, kT0);
  w.open(kT0);
  // A file size limit makes write(2) fail with EFBIG like a full disk fails with ENOSPC.
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  auto* old_handler = std::signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 20000;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  int failed = 0;
  for (int i = 0; i < 400; ++i)
    if (!w.write(kT0 + i, "CH", payload(i).data(), 100, kT0 + i)) ++failed;
  w.flush(kT0 + 500);
  setrlimit(RLIMIT_FSIZE, &old);
  std::signal(SIGXFSZ, old_handler);

  EXPECT_GT(failed, 0);
  EXPECT_GE(w.counters().write_errors, 1);
  EXPECT_GT(w.counters().events_lost, 0);
  EXPECT_NE(w.last_error().find(w.files().front()), std::string::npos) << w.last_error();
  EXPECT_NE(w.last_error().find("File too large"), std::string::npos) << w.last_error();
  const status_t st = w.make_status(kT0 + 600);
  EXPECT_EQ(st.last_error, w.last_error());
  EXPECT_EQ(find_counter(st, "drops"), w.counters().events_lost);
  // The first file is readable up to where it failed.
  EXPECT_GT(data_events(read_with_logfile(w.files().front()), o.status_channel).size(), 50u);

  // After the reopen interval the next event opens a new file, whose first status event says
  // what went wrong.
  ASSERT_TRUE(w.write(kT0, "CH", "z", 1, kT0 + 2'000'000));
  w.close(kT0 + 2'100'000);
  ASSERT_EQ(w.files().size(), 2u);
  const auto st2 = status_events(read_with_logfile(w.files().back()), o.status_channel);
  ASSERT_FALSE(st2.empty());
  EXPECT_NE(st2.front().last_error.find("File too large"), std::string::npos);
  EXPECT_GE(find_counter(st2.front(), "write_errors").value_or(0), 1);
}

// A full disk (a 256 kB tmpfs in a private mount namespace, most of it taken by a filler file):
// one file, cut at its last whole event, events counted as lost with one error naming the file
// and ENOSPC, and written on to the same file once the filler is deleted.
TEST(EventLogWriter, AFullDiskKeepsOneValidFileAndWritesOnWhenSpaceReturns) {
  TempDir dir;
  if (::unshare(CLONE_NEWNS) != 0 || ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0 ||
      ::mount("tmpfs", dir.path().c_str(), "tmpfs", 0, "size=256k") != 0)
    GTEST_SKIP() << "needs a private mount namespace and a tmpfs (root): " << std::strerror(errno);
  struct Unmount {
    std::string path;
    ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
  } unmount{dir.path()};
  const std::string filler = dir.path() + "/filler";
  {
    std::ofstream f(filler, std::ios::binary);
    f << std::string(200 * 1024, 'f');
  }
  auto o = options_in(dir);
  o.buffer_bytes = 4096;
  o.reopen_interval_s = 1.0;
  EventLogWriter w(o, kT0);
  w.open(kT0);
  std::int64_t t = kT0, failed = 0;
  for (int i = 0; i < 400; ++i, t += 10'000)  // 400 kB of events into the ~50 kB left, over 4 s of retries
    if (!w.write(t, "CH", payload(i, 1000).data(), 1000, t)) ++failed;
  w.flush(t);
  ASSERT_TRUE(w.disk_full());
  EXPECT_GT(failed, 300);
  EXPECT_EQ(w.counters().write_errors, 1);  // one error however long the disk stays full
  EXPECT_EQ(w.counters().disk_full_episodes, 1);
  EXPECT_NE(w.last_error().find(w.current_path()), std::string::npos) << w.last_error();
  EXPECT_NE(w.last_error().find("No space left on device"), std::string::npos) << w.last_error();
  EXPECT_EQ(w.make_status(t).state, "disk full");
  ASSERT_EQ(w.files().size(), 1u);
  EXPECT_EQ(problems_in(w.current_path()), 0);  // cut at its last whole event
  const auto before = data_events(read_with_logfile(w.current_path()), o.status_channel).size();
  EXPECT_GT(before, 20u);
  EXPECT_EQ(std::int64_t(before) + w.counters().events_lost, 400);
  EXPECT_EQ(w.counters().events, std::int64_t(before));

  // Space returns: after the retry interval the events go into the same file.
  ASSERT_EQ(std::remove(filler.c_str()), 0);
  t += 1'100'000;
  for (int i = 400; i < 450; ++i, t += 1000) EXPECT_TRUE(w.write(t, "CH", payload(i, 1000).data(), 1000, t));
  EXPECT_FALSE(w.disk_full());
  EXPECT_EQ(w.make_status(t).state, "running");
  w.close(t);
  ASSERT_EQ(w.files().size(), 1u);
  EXPECT_EQ(problems_in(w.files().front()), 0);
  const auto all = read_with_logfile(w.files().front());
  const auto data = data_events(all, o.status_channel);
  ASSERT_EQ(data.size(), before + 50);
  EXPECT_EQ(data.back().data, payload(449, 1000));
  const auto st = status_events(all, o.status_channel);
  const auto resumed = std::find_if(st.begin(), st.end(), [](const status_t& s) { return s.state == "resumed"; });
  ASSERT_NE(resumed, st.end());
  EXPECT_EQ(find_counter(*resumed, "events_lost"), 400 - std::int64_t(before));
  EXPECT_NE(resumed->last_error.find("No space left on device"), std::string::npos);
}

TEST(EventLogWriter, CountsSampleSequenceGapsPerBench) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  auto put = [&](const std::string& bench, std::int64_t seq, int n) {
    const auto m = encode_samples(bench, seq, n);
    w.write(kT0, "SPINDOWN." + bench + ".SAMPLE", m.data(), static_cast<std::int32_t>(m.size()), kT0);
  };
  put("a", 0, 4);
  put("a", 4, 4);
  put("b", 100, 1);
  put("a", 12, 4);  // 8..11 missing
  put("b", 101, 1);
  put("a", 0, 4);   // a restarted bridge
  w.write(kT0, "SPINDOWN.a.SAMPLE", "junk", 4, kT0);
  EXPECT_EQ(w.counters().seq_gaps, 0);  // 8..11 may still come (the reorder window)
  w.tick(kT0 + ReorderOptions{}.window_us);
  EXPECT_EQ(w.counters().seq_gaps, 1);
  EXPECT_EQ(w.counters().samples_missing, 4);
  EXPECT_EQ(w.counters().seq_repeats, 4);  // the samples of the repeated message
  EXPECT_EQ(w.counters().decode_errors, 1);
  EXPECT_EQ(w.counters().events, 7);  // undecodable events are still logged
}

// The stream's first datagrams overtaken (jitter between the PCs): 1, then 5, then 0 … The first
// heard waits for what it overtook; nothing is a repeat or missing (before: seq 0 was "repeated").
// A bench first heard far past 0 (a logger started mid-session) starts there after the window.
TEST(EventLogWriter, AStreamWhoseFirstDatagramsWereOvertakenCountsNothing) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  auto put = [&](const std::string& bench, std::int64_t seq, std::int64_t at) {
    const auto m = encode_samples(bench, seq, 1);
    w.write(at, "SPINDOWN." + bench + ".SAMPLE", m.data(), static_cast<std::int32_t>(m.size()), at);
  };
  std::int64_t at = kT0;
  for (int seq : {1, 5, 0, 4, 2, 3, 6, 8, 7, 9}) put("a", seq, at += 20'000);
  for (int seq = 7000; seq < 7010; ++seq) put("b", seq, at += 20'000);
  w.tick(at + ReorderOptions{}.window_us);
  put("b", 7010, at += 20'000);
  w.tick(at + ReorderOptions{}.window_us);
  EXPECT_EQ(w.counters().seq_repeats, 0);
  EXPECT_EQ(w.counters().samples_missing, 0);
  EXPECT_EQ(w.counters().seq_gaps, 0);
}

// The lab's gate refused them (forged, replayed, another key): written, never counted as the
// lab's loss, repeats or late samples (issue 42: a forger made 5 million "missing" samples).
TEST(EventLogWriter, RefusedMessagesAreWrittenButNotCountedInTheSequence) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  auto put = [&](std::int64_t seq, bool accepted) {
    const auto m = encode_samples("a", seq, 1);
    w.write(kT0, "SPINDOWN.a.SAMPLE", m.data(), static_cast<std::int32_t>(m.size()), kT0, accepted);
  };
  for (int i = 0; i < 10; ++i) {
    put(i, true);
    put(1'000'000 + 7 * i, false);  // a forged stream under the bridge's session
    put(i, false);                  // a replay of the real one
  }
  w.tick(kT0 + 10 * ReorderOptions{}.window_us);
  EXPECT_EQ(w.counters().seq_gaps, 0);
  EXPECT_EQ(w.counters().samples_missing, 0);
  EXPECT_EQ(w.counters().seq_repeats, 0);
  EXPECT_EQ(w.counters().events, 30);
}

TEST(LogRecorder, DrainsEverythingQueuedOnStop) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  LogRecorderOptions ro;
  ro.queue_capacity = 100000;
  LogRecorder r(w, ro);
  r.start();
  for (int i = 0; i < 20000; ++i) ASSERT_TRUE(r.offer(kT0 + i, "CH", payload(i).data(), 100));
  r.stop("stopped");
  EXPECT_FALSE(w.is_open());
  EXPECT_EQ(w.counters().events, 20000);
  const auto all = read_with_logfile(w.files().front());
  const auto data = data_events(all, w.options().status_channel);
  ASSERT_EQ(data.size(), 20000u);
  EXPECT_EQ(data.back().data, payload(19999));
  EXPECT_EQ(find_counter(r.status(kT0), "events"), 20000);
}

TEST(LogRecorder, DropsPastTheQueueAreCountedInStatusAndLog) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  LogRecorderOptions ro;
  ro.queue_capacity = 5;
  LogRecorder r(w, ro);
  int accepted = 0;
  for (int i = 0; i < 12; ++i) accepted += r.offer(kT0 + i, "CH", "x", 1);  // writer not started yet
  EXPECT_EQ(accepted, 5);
  EXPECT_EQ(r.dropped(), 7);
  r.start();
  r.stop("stopped");
  EXPECT_EQ(w.counters().events, 5);
  EXPECT_EQ(find_counter(r.status(kT0), "queue_drops"), 7);
  EXPECT_EQ(find_counter(r.status(kT0), "drops"), 7);
  const auto st = status_events(read_with_logfile(w.files().front()), w.options().status_channel);
  ASSERT_FALSE(st.empty());
  EXPECT_EQ(st.back().state, "stopped");
  EXPECT_EQ(find_counter(st.back(), "drops"), 7);
}

// A message larger than max_event_bytes (LCM assembling what a forged fragment header claims)
// is not recorded: counted as oversize_drops, named in the status and the log's heartbeat; the
// messages around it are kept.
TEST(LogRecorder, AnOversizeMessageIsCountedAndNamedNotRecorded) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  LogRecorderOptions ro;
  ro.max_event_bytes = 4096;
  LogRecorder r(w, ro);
  r.start();
  const std::vector<char> big(5000, 'z');
  EXPECT_TRUE(r.offer(kT0, "CH", payload(0).data(), 100));
  EXPECT_FALSE(r.offer(kT0 + 1, "SPINDOWN.x.SAMPLE", big.data(), static_cast<std::int32_t>(big.size())));
  EXPECT_TRUE(r.offer(kT0 + 2, "CH", payload(1).data(), 100));
  r.stop("stopped");
  EXPECT_EQ(w.counters().events, 2);
  EXPECT_EQ(w.counters().oversize_drops, 1);
  const auto st = status_events(read_with_logfile(w.files().front()), w.options().status_channel);
  ASSERT_FALSE(st.empty());
  EXPECT_EQ(find_counter(st.back(), "oversize_drops"), 1);
  EXPECT_NE(st.back().last_error.find("message of 5000 bytes on SPINDOWN.x.SAMPLE not recorded"), std::string::npos)
      << st.back().last_error;
  EXPECT_EQ(data_events(read_with_logfile(w.files().front()), w.options().status_channel).size(), 2u);
}

TEST(LogRecorder, FlushesOnItsTimerWithoutFurtherMessages) {
  TempDir dir;
  EventLogWriter w(options_in(dir), kT0);
  w.open(kT0);
  const std::string path = w.current_path();
  LogRecorderOptions ro;
  ro.flush_interval_s = 0.05;
  LogRecorder r(w, ro);
  r.start();
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(r.offer(kT0 + i, "CH", payload(i).data(), 100));
  // Nothing else arrives; the events must reach the file anyway (bounded wait).
  std::size_t on_disk = 0;
  for (int i = 0; i < 500 && on_disk < 3; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    on_disk = data_events(read_with_logfile(path), w.options().status_channel).size();
  }
  EXPECT_EQ(on_disk, 3u);
  r.stop();
}

TEST(StatusHeartbeat, NamedCountersAndGaugesKeepTheirOrder) {
  StatusHeartbeat hb("fitter", "lab", kT0, 1.0, "host-a", 42);
  hb.set_state("running");
  hb.set_counter("samples", 10);
  hb.add_counter("decode_errors");
  hb.add_counter("samples", 5);
  hb.set_gauge("rate_hz", 50);
  hb.set_error("bench x: NaN value", kT0 + 5);
  const status_t st = hb.message(kT0 + 2'000'000);
  EXPECT_EQ(st.service, "fitter");
  EXPECT_EQ(st.instance, "lab");
  EXPECT_EQ(st.host, "host-a");
  EXPECT_EQ(st.pid, 42);
  EXPECT_EQ(st.state, "running");
  EXPECT_DOUBLE_EQ(st.uptime_s, 2.0);
  ASSERT_EQ(st.ncounters, 2);
  EXPECT_EQ(st.counter_name[0], "samples");
  EXPECT_EQ(st.counter_value[0], 15);
  EXPECT_EQ(find_counter(st, "decode_errors"), 1);
  EXPECT_EQ(find_gauge(st, "rate_hz"), 50.0);
  EXPECT_FALSE(find_counter(st, "nope").has_value());
  EXPECT_EQ(st.last_error, "bench x: NaN value");
  EXPECT_EQ(st.last_error_utime, kT0 + 5);
}

TEST(StatusHeartbeat, DueOncePerIntervalWithoutCatchUpBursts) {
  StatusHeartbeat hb("logger", "x", kT0, 1.0);
  EXPECT_TRUE(hb.due(kT0));
  hb.mark_sent(kT0);
  EXPECT_FALSE(hb.due(kT0 + 999'999));
  EXPECT_TRUE(hb.due(kT0 + 1'000'000));
  hb.mark_sent(kT0 + 10'000'000);  // a long stall
  EXPECT_FALSE(hb.due(kT0 + 10'500'000));
  EXPECT_TRUE(hb.due(kT0 + 11'000'000));
}

TEST(StatusHeartbeat, PublishesOnLcm) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  // A C callback, not LCM's C++ subscribe template: under UBSan the 1.3.1 template's memq
  // dispatch reports a null subscription pointer inside LCM's own header.
  std::vector<status_t> got;
  auto on_status = [](const lcm_recv_buf_t* rbuf, const char*, void* user) {
    status_t st{};
    if (st.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0)
      static_cast<std::vector<status_t>*>(user)->push_back(st);
  };
  lcm_subscription_t* sub = lcm_subscribe(lcm.getUnderlyingLCM(), "SPINDOWN.logger.STATUS", on_status, &got);
  ASSERT_NE(sub, nullptr);
  StatusHeartbeat hb("logger", "x", kT0);
  hb.set_counter("events", 3);
  ASSERT_EQ(hb.publish(lcm, "SPINDOWN.logger.STATUS", kT0), 0);
  for (int i = 0; i < 10 && got.empty(); ++i) lcm.handleTimeout(100);
  lcm_unsubscribe(lcm.getUnderlyingLCM(), sub);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(find_counter(got[0], "events"), 3);
  EXPECT_FALSE(hb.due(kT0 + 10));
}
