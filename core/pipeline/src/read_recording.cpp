#include "spindown/read_recording.hpp"

#include "spindown/held_readings.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <limits>
#include <cstdint>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <memory>
#include <sys/stat.h>
#include <unistd.h>

#include "spindown/column_guess.hpp"
#include "spindown/file_bytes.hpp"
#include "spindown/lab_line.hpp"
#include "spindown/spindown_protocol.hpp"
#include "spindown/text_repairs.hpp"
#include "spindown/text_support.hpp"
#include "spindown/trim.hpp"

namespace spindown {

std::string_view file_format_name(FileFormat format) {
  switch (format) {
    case FileFormat::automatic: return "auto";
    case FileFormat::arduino_text: return "arduino";
    case FileFormat::delimited_text: return "delimited";
    case FileFormat::lcm_log: return "lcm";
    case FileFormat::spindown_v1: return spindown_protocol_name;
  }
  return "?";
}

std::optional<FileFormat> parse_file_format(std::string_view name) {
  if (name == "auto") return FileFormat::automatic;
  if (name == "arduino" || name == "putty" || name == "lab") return FileFormat::arduino_text;
  if (name == "delimited" || name == "csv" || name == "tsv" || name == "text") return FileFormat::delimited_text;
  if (name == "lcm" || name == "lcm-log" || name == "log") return FileFormat::lcm_log;
  if (name == spindown_protocol_name || name == "v1" || name == "spindown") return FileFormat::spindown_v1;
  return std::nullopt;
}

bool ReadOptions::is_valid(std::string* why) const {
  std::string w;
  if (!arduino.is_valid(&w)) {
    if (why) *why = "Arduino text: " + w;
    return false;
  }
  if (!delimited.is_valid(&w)) {
    if (why) *why = "delimited text: " + w;
    return false;
  }
  if (!lcm.is_valid(&w)) {
    if (why) *why = "LCM log: " + w;
    return false;
  }
  if (!spindown.is_valid(&w)) {
    if (why) *why = "spindown-v1 text: " + w;
    return false;
  }
  return true;
}

namespace {

// Regular files up to this size are read whole before their format is known.
constexpr std::uintmax_t whole_read_bytes = 1 << 20;

}  // namespace


FileFormat detect_format(std::string_view head, const ReadOptions& options) {
  if (head.size() >= 4) {
    const auto* p = reinterpret_cast<const unsigned char*>(head.data());
    const std::uint32_t word =
        (std::uint32_t(p[0]) << 24) | (std::uint32_t(p[1]) << 16) | (std::uint32_t(p[2]) << 8) | p[3];
    if (word == lcm_log_magic) return FileFormat::lcm_log;
  }
  if (options.format != FileFormat::automatic) return options.format;
  if (options.delimited.names_columns()) return FileFormat::delimited_text;
  // A header whose units the lab's millis<TAB>volts reader would not honour ("millis<TAB>rpm").
  {
    text::LineCursor first(head.substr(0, 64 * 1024));
    while (!first.at_end()) {
      const std::string_view line = trim(first.next_line());
      if (line.empty() || line.front() == '#' || line.starts_with("=~=~=~")) continue;
      if (header_needs_delimited_reader(line)) return FileFormat::delimited_text;
      break;
    }
  }
  // A spindown-v1 capture when the firmware's banner is there or at least half of the first 50
  // lines with content are its samples (checksums valid: no other text passes for one), else
  // Arduino text when at least half are lab samples.
  std::size_t content = 0, samples = 0, v1_samples = 0;
  text::LineCursor lines(head.substr(0, 64 * 1024));
  while (content < 50 && !lines.at_end()) {  // stop there: splitting the rest cost as much as parsing it
    LabLine printed;
    if (const std::size_t length = parse_printed_sample(lines.rest(), printed)) {  // the usual line, quickly
      lines.skip_line(length);
      ++content;
      ++samples;
      continue;
    }
    const std::string_view line = lines.next_line();
    if (line.starts_with("=~=~=~")) continue;
    if (looks_like_spindown_line(line)) {
      const SpindownLine v1 = parse_spindown_line(line);
      if (v1.kind == SpindownLine::Kind::banner) return FileFormat::spindown_v1;
      if (v1.kind == SpindownLine::Kind::sample) {
        ++content;
        ++v1_samples;
        continue;
      }
    }
    const LabLine parsed = parse_lab_line(line);
    if (parsed.kind == LabLine::Kind::blank) continue;
    ++content;
    samples += parsed.kind == LabLine::Kind::sample;
  }
  if (v1_samples > 0 && v1_samples * 2 >= content) return FileFormat::spindown_v1;
  if (content == 0 || samples * 2 >= content) return FileFormat::arduino_text;
  return FileFormat::delimited_text;
}

namespace {

// Two columns the other way round ("volts<TAB>millis"): the lab's reader took the volts for times
// and dropped most lines as "time repeats". When the numbers say the time is another column
// (column_guess.hpp, as for a table without names), the recording is refused with the options
// that read it; nothing is fitted from the wrong column.
void refuse_swapped_columns(std::string_view bytes, Recording& rec) {
  if (rec.lines_read < 20 || rec.size() * 2 >= rec.lines_read) return;
  std::vector<std::vector<double>> cols;
  std::size_t rows = 0;
  text::LineCursor lines(bytes.substr(0, 64 * 1024));
  while (!lines.at_end() && rows < 400) {
    const std::string_view line = trim(lines.next_line());
    std::vector<double> row;
    std::size_t at = 0;
    while (at < line.size()) {
      const std::size_t end = line.find_first_of(" \t,;", at);
      const std::string_view f = line.substr(at, end == std::string_view::npos ? std::string_view::npos : end - at);
      double x = 0;
      const auto [p, ec] = std::from_chars(f.data(), f.data() + f.size(), x);
      row.push_back(ec == std::errc() && p == f.data() + f.size() ? x : std::numeric_limits<double>::quiet_NaN());
      if (end == std::string_view::npos) break;
      at = line.find_first_not_of(" \t,;", end);
    }
    if (row.size() < 2 || std::isnan(row[0]) || std::isnan(row[1])) continue;
    if (cols.empty()) cols.resize(row.size());
    if (row.size() != cols.size()) continue;
    for (std::size_t c = 0; c < row.size(); ++c) cols[c].push_back(row[c]);
    ++rows;
  }
  if (rows < 20) return;
  const ColumnGuess guess = guess_columns(cols);
  if (guess.time <= 0) return;
  const auto proposal = column_proposal(guess);
  if (!proposal) return;
  rec.t_s.clear();
  rec.value.clear();
  rec.clock_restarts.clear();
  // The lines' own complaints ("time 0 s repeats") were about the wrong column: the error says it.
  std::erase_if(rec.diagnostics, [](const Diagnostic& d) { return d.line > 0 && d.severity == Diagnostic::Severity::warning; });
  rec.error(0, fmt::format("column 1 is no time ({} of {} lines not used as samples): the columns are not "
                           "millis<TAB>volts in that order; {}",
                           rec.lines_read - rec.size(), rec.lines_read, *proposal));
}

// Every reading negative (a differential probe's leads swapped, a motor turned the other way):
// no coast rises from rest in it. Read as their magnitude, and said.
void read_negative_as_magnitude(Recording& rec) {
  // Counts, stopping as soon as the positive ones are too many for the negative ones ever to be
  // twenty times as many (at once in a recording of the usual sign).
  const std::size_t n = rec.value.size();
  std::size_t negative = 0, positive = 0;
  for (std::size_t i = 0; i < n; ++i) {
    negative += rec.value[i] < 0;
    positive += rec.value[i] > 0;
    if ((i & 63) == 63 && positive * 20 > negative + (n - 1 - i)) return;
  }
  if (negative < 20 || positive * 20 > negative) return;
  const double lowest = *std::min_element(rec.value.begin(), rec.value.end());
  // A coast, not a rest's noise a step below zero: it passes through many values.
  std::vector<double> levels;
  for (const double v : rec.value)
    if (v < 0 && levels.size() < 20 && std::find(levels.begin(), levels.end(), v) == levels.end()) levels.push_back(v);
  if (levels.size() < 20) return;
  for (double& v : rec.value) v = -v;
  rec.warn(0, fmt::format("{} of {} readings are negative (down to {:g}) and {} positive: the probe's leads are the "
                          "wrong way round (or the motor turned the other way); read as their magnitude",
                          negative, rec.size(), lowest, positive));
}

Recording failed(const std::string& path, std::string message) {
  Recording rec;
  rec.source = path;
  rec.error(0, std::move(message));
  return rec;
}

}  // namespace

std::vector<Recording> read_recordings(const std::string& path, const ReadOptions& options,
                                       std::vector<RecordingInfo>* info) {
  std::vector<Recording> out;
  auto add = [&](Recording rec, RecordingInfo i) {
    out.push_back(std::move(rec));
    if (info) info->push_back(std::move(i));
  };
  if (info) info->clear();
  std::string why;
  if (!options.is_valid(&why)) {
    add(failed(path, "invalid read options: " + why), {});
    return out;
  }

  // An LCM log is streamed by lcm::LogFile, which seeks (so it cannot come through a pipe); its
  // first word says what it is. Text is read whole through the same descriptor (one open per file).
  std::optional<FileBytes> text_bytes;
  bool lcm_log = false;
  {
    const int fd = open_for_reading(path);
    if (fd < 0) {
      add(failed(path, fmt::format("cannot open {}: {}", path, std::strerror(errno))), {});
      return out;
    }
    FdCloser closer{fd};
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
      add(failed(path, fmt::format("cannot read {}: {}", path, std::strerror(errno))), {});
      return out;
    }
    reads_blocking(fd, st);
    if (S_ISDIR(st.st_mode)) {
      add(failed(path, fmt::format("cannot read {}: it is a directory", path)), {});
      return out;
    }
    const auto read_whole = [&] {
      text_bytes = read_fd_bytes(fd, st, path, &why, std::size_t{1} << 30);
      if (!text_bytes) add(failed(path, why), {});
      return text_bytes.has_value();
    };
    // Read whole first: a pipe, FIFO or device (it can be read only once), or a small regular
    // file (a lab's text file is ~20 kB: its first word is then looked at in its bytes, one
    // system call fewer than reading the word first). Otherwise the first word is read alone.
    const bool regular = S_ISREG(st.st_mode);
    char head[4] = {};
    std::string_view first_word;
    if (!regular ||
        (options.format != FileFormat::lcm_log && static_cast<std::uintmax_t>(st.st_size) <= whole_read_bytes)) {
      if (!read_whole()) return out;
      first_word = text_bytes->view().substr(0, sizeof head);
    } else {
      const ssize_t n = ::pread(fd, head, sizeof head, 0);
      first_word = std::string_view(head, n > 0 ? static_cast<std::size_t>(n) : 0);
    }
    lcm_log = detect_format(first_word, options) == FileFormat::lcm_log || options.format == FileFormat::lcm_log;
    if (lcm_log && !regular) {
      add(failed(path, fmt::format("cannot read {} as an LCM log: it is a pipe or device, and lcm::LogFile needs a "
                                   "regular file",
                                   path)),
          {});
      return out;
    }
    if (lcm_log) text_bytes.reset();  // a small log read whole: streamed as any log is
    else if (!text_bytes && !read_whole()) return out;
  }

  if (lcm_log) {
    LcmLogContents log = read_lcm_log(path, options.lcm);
    for (BenchLog& b : log.benches) {
      if (b.sample_messages == 0) continue;
      Recording rec = std::move(b.recording);
      rec.diagnostics.insert(rec.diagnostics.begin(), log.diagnostics.begin(), log.diagnostics.end());
      add(std::move(rec), {FileFormat::lcm_log, b.bench, std::move(b.config), b.samples_lost});
    }
    if (out.empty()) {
      Recording rec;
      rec.source = path;
      rec.diagnostics = log.diagnostics;
      if (!log.has_errors()) {
        std::string channels;
        for (const auto& [name, count] : log.other_channels)
          if (channels.size() < 300)
            channels += fmt::format("{}{} ({})", channels.empty() ? "" : ", ", text::escape_invalid_utf8(name), count);
        for (const BenchLog& b : log.benches)
          channels += fmt::format("{}SPINDOWN.{}.CONFIG ({})", channels.empty() ? "" : ", ", b.bench,
                                  b.config_messages);
        rec.error(0, fmt::format("no samples: {} events, none on SPINDOWN.<bench>.SAMPLE{}", log.events,
                                 channels.empty() ? std::string() : " (channels: " + channels + ")"));
      }
      add(std::move(rec), {FileFormat::lcm_log, {}, {}, 0});
    }
    return out;
  }

  std::string_view bytes = text_bytes->view();
  // What editors and terminals did to the text, undone (text_repairs.hpp); lines stay in place.
  std::string repaired;
  std::vector<std::string> repairs;
  if (needs_text_repair(bytes)) {
    repaired.assign(bytes);
    repairs = repair_text(repaired);
    bytes = repaired;
  }
  const FileFormat format = detect_format(bytes, options);
  if (format == FileFormat::delimited_text) {
    Recording rec = read_delimited_text(bytes, path, options.delimited);
    take_held_readings_once(rec);  // a slower channel logged in every row: each reading once
    read_negative_as_magnitude(rec);
    add(std::move(rec), {FileFormat::delimited_text, {}, {}, 0});
  } else if (format == FileFormat::spindown_v1) {
    std::int64_t lost = 0;
    Recording rec = read_spindown_text(bytes, path, options.spindown, &lost);
    add(std::move(rec), {FileFormat::spindown_v1, {}, {}, lost});
  } else {
    Recording rec = read_arduino_text(bytes, path, options.arduino);
    refuse_swapped_columns(bytes, rec);
    read_negative_as_magnitude(rec);
    add(std::move(rec), {FileFormat::arduino_text, {}, {}, 0});
  }
  for (auto it = repairs.rbegin(); it != repairs.rend(); ++it)
    out.back().diagnostics.insert(out.back().diagnostics.begin(),
                                  Diagnostic{Diagnostic::Severity::note, path, 0, std::move(*it)});
  return out;
}

std::optional<BenchParams> config_bench_params(const RecordingInfo* info, const std::string& source,
                                               std::vector<Diagnostic>& diags) {
  if (!info || !info->config) return std::nullopt;
  std::string why;
  if (auto b = bench_params_from_config(*info->config, &why)) return b;
  diags.push_back({Diagnostic::Severity::warning, source, 0,
                   fmt::format("bench config not used ({}); J and K_b from the command line, the bench file or the "
                               "lab's defaults",
                               why)});
  return std::nullopt;
}

}  // namespace spindown
