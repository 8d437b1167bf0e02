// LCM event logs: the input is the file. lcm::LogFile only opens paths, so the bytes go to an
// in-memory file (memfd) opened through /proc/self/fd. Read three ways: the streaming reader
// event by event, read_lcm_log (one Recording per bench) and read_recordings (format detection).
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_check.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/read_recording.hpp"

namespace {

const std::string& log_path(const std::uint8_t* data, std::size_t size) {
  static const int fd = memfd_create("fuzz.lcmlog", 0);
  static const std::string path = "/proc/self/fd/" + std::to_string(fd);
  FUZZ_CHECK(fd >= 0);
  FUZZ_CHECK(ftruncate(fd, 0) == 0);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = pwrite(fd, data + done, size - done, static_cast<off_t>(done));
    FUZZ_CHECK(n > 0);
    done += static_cast<std::size_t>(n);
  }
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace spindown;
  const std::string& path = log_path(data, size);

  {
    LcmLogReader reader(path);
    FUZZ_CHECK(reader.good());
    LcmLogEvent event;
    std::int64_t calls = 0;
    std::int64_t last_offset = -1;
    while (reader.next(event)) {
      // Every call moves on: at most one event or one problem per byte, plus the end.
      FUZZ_CHECK(++calls <= static_cast<std::int64_t>(size) + 2);
      if (event.kind == LcmLogEvent::Kind::problem) FUZZ_CHECK(!event.problem.empty() && fuzz::valid_utf8(event.problem));
      if (event.kind == LcmLogEvent::Kind::samples) {
        FUZZ_CHECK(event.samples.n >= 0);
        FUZZ_CHECK(event.samples.value.size() == static_cast<std::size_t>(event.samples.n));
      }
      FUZZ_CHECK(event.file_offset >= 0 && event.file_offset <= static_cast<std::int64_t>(size));
      last_offset = event.file_offset;
    }
    (void)last_offset;
  }

  LcmLogOptions options;
  options.max_event_reports = 5;
  const LcmLogContents contents = read_lcm_log(path, options);
  for (const BenchLog& bench : contents.benches) {
    // Log recordings keep device time as sent; a bench may have sent only CONFIG (no samples,
    // no error: read_recordings leaves it out).
    fuzz::check_recording(bench.recording, false, false);
    FUZZ_CHECK(bench.samples_lost >= 0);
  }

  const std::vector<Recording> recs = read_recordings(path);
  FUZZ_CHECK(!recs.empty());
  for (const Recording& rec : recs) fuzz::check_recording(rec, false);
  return 0;
}
