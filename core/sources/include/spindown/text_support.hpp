#pragma once
// Shared by the text readers (Arduino/PuTTY and delimited text): splitting a buffer into
// lines, reporting bad lines without flooding the output, and turning the samples' printed
// device times into a Recording's timeline (cut first line, wrap, reset, outliers,
// duplicates). The LCM log reader uses its quoting and its bad-line reporting too; users of
// the readers want arduino_text.hpp and delimited_text.hpp.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/file_bytes.hpp"
#include "spindown/recording.hpp"
#include "spindown/text_encoding.hpp"
#include "spindown/utf8_text.hpp"

namespace spindown::text {

// Walks text line by line. LF, CR LF and a lone CR (old Mac, some terminal programs) all end
// a line; a final line without a terminator counts too. For readers that look at a line's
// start before they know where it ends (the Arduino reader's fast path). No allocation.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : p_(text.data()), end_(text.data() + text.size()) {}

  bool at_end() const { return p_ >= end_; }
  // From the next line's start to the end of text.
  std::string_view rest() const { return {p_, static_cast<std::size_t>(end_ - p_)}; }
  // Number of the line last taken (1-based); after the last one, the number of lines.
  std::int64_t line_number() const { return number_; }

  // Takes the next line and returns it without its terminator.
  std::string_view next_line() {
    if (nl_ == nullptr || nl_ < p_) {
      nl_ = static_cast<const char*>(std::memchr(p_, '\n', static_cast<std::size_t>(end_ - p_)));
      if (!nl_) nl_ = end_;
    }
    const char* cr = static_cast<const char*>(std::memchr(p_, '\r', static_cast<std::size_t>(nl_ - p_)));
    const char* stop = cr ? cr : nl_;
    const std::string_view line(p_, static_cast<std::size_t>(stop - p_));
    step_past(stop);
    return line;
  }

  // Takes the next line when the caller has seen that it is `length` bytes long and ends
  // there (at a CR, an LF or the end of text).
  void skip_line(std::size_t length) { step_past(p_ + length); }

  // Takes `lines` whole lines the caller has read, `bytes` long with their terminators.
  void skip_lines(std::size_t bytes, std::size_t lines) {
    p_ += bytes;
    number_ += static_cast<std::int64_t>(lines);
  }

 private:
  void step_past(const char* stop) {
    ++number_;
    if (stop == end_) {
      p_ = end_;
      return;
    }
    p_ = stop + 1;
    if (*stop == '\r' && p_ < end_ && *p_ == '\n') ++p_;
  }

  const char* p_;
  const char* end_;
  const char* nl_ = nullptr;  // next '\n' at or after p_ (or end_); kept so CR-only text stays O(n)
  std::int64_t number_ = 0;
};

// Calls on_line(line_number, line) for each line of text, without its terminator (lines as
// LineCursor splits them). Returns the number of lines.
template <class OnLine>
std::int64_t for_each_line(std::string_view text, OnLine&& on_line) {
  LineCursor lines(text);
  while (!lines.at_end()) {
    const std::string_view line = lines.next_line();
    on_line(lines.line_number(), line);
  }
  return lines.line_number();
}

// True when the bytes are not text: more than 10 % control characters (NUL included; tab,
// CR, LF excepted) in the first 8 KiB. A few bytes of serial noise do not make a log binary.
bool looks_binary(std::string_view bytes, std::size_t* control_bytes = nullptr,
                  std::size_t* looked_at = nullptr);

// looks_binary's verdict, reached while a reader walks the text from its start and hands in
// only the bytes its slow path reads. Its fast path takes lines of digits, signs, points, blanks
// and line ends, never control bytes, so a lab file's PuTTY header is counted instead of its
// first 8 KiB (which cost as much as parsing 140 lines).
class BinaryCheck {
 public:
  explicit BinaryCheck(std::string_view text);
  // The bytes [from, to) of the text were read some other way than the fast path.
  void count(const char* from, const char* to);
  // True once the reader at `at` has passed every byte looks_binary looks at.
  bool decided(const char* at) const { return static_cast<std::size_t>(at - begin_) >= looked_at_; }
  // Valid once decided: what looks_binary(text, &control_bytes, &looked_at) gives.
  bool binary() const { return looked_at_ > 0 && control_bytes_ * 10 > looked_at_; }
  std::size_t control_bytes() const { return control_bytes_; }
  std::size_t looked_at() const { return looked_at_; }

 private:
  const char* begin_;
  std::size_t looked_at_;
  std::size_t control_bytes_ = 0;
};

// "no samples: binary data, not WHAT (N of the first M bytes are control characters or NUL)".
std::string binary_data_error(std::string_view what, std::size_t control_bytes, std::size_t looked_at);

// A line for a message: quoted, control bytes and bytes that are not UTF-8 escaped (\xNN),
// cut to 40 characters (never inside one). Messages stay valid UTF-8, which JSON needs.
std::string quote_line(std::string_view line);

// Per-line problems go to the Recording one by one up to a limit, then only as a count, so
// a file of garbage still gives readable output.
class LineReporter {
 public:
  LineReporter(Recording& recording, std::size_t max_individual)
      : rec_(recording), max_(max_individual) {}
  void report(Diagnostic::Severity severity, std::int64_t line, std::string message);
  void warn(std::int64_t line, std::string message) {
    report(Diagnostic::Severity::warning, line, std::move(message));
  }
  // The summary of what was not listed; call once at the end.
  void finish();
  std::size_t count() const { return count_; }

 private:
  Recording& rec_;
  std::size_t max_;
  std::size_t count_ = 0;
  std::int64_t first_unlisted_ = 0, last_unlisted_ = 0;  // lowest and highest line not listed
  std::size_t unlisted_[3] = {};                          // by severity
};

// Diagnostics in line order, those about the whole file (line 0) last; stable.
void sort_by_line(Recording& rec);

// "PuTTY log header skipped (log started 2023.09.14 10:21:33)" for a PuTTY header line.
std::string putty_header_note(std::string_view line);

// The parsed samples before timeline repair, as two arrays the readers append to (t in the
// file's own unit, ms for millis()). Where a sample came from (its line, the line's text, whether
// it starts a logging session) is needed only for messages, so it is kept per block of samples
// from consecutive lines rather than per sample.
class RawSamples {
 public:
  // A block's lines are walked to find a sample's text: at most this many. Each block costs the
  // readers a few hundred instructions (a fast-path call, a timeline check), ~5 a line at 128.
  static constexpr std::size_t block_lines = 128;

  // text: the whole file, which the lines' texts point into.
  explicit RawSamples(std::string_view text) : text_end_(text.data() + text.size()) {}

  std::vector<double> t, value;

  std::size_t size() const { return t.size(); }
  void reserve(std::size_t n) {
    t.reserve(n);
    value.reserve(n);
  }
  // Appends one sample, read from line number `line` that starts at line_start.
  void add(std::int64_t line, const char* line_start, double time, double v, bool session_start) {
    t.push_back(time);
    value.push_back(v);
    const std::size_t i = t.size() - 1;
    if (blocks_.empty() || session_start || blocks_.back().first_line + static_cast<std::int64_t>(i - blocks_.back().first) != line ||
        i - blocks_.back().first >= block_lines)
      blocks_.push_back({i, line, line_start, session_start});
  }
  // The samples from index first to the end, appended to t and value by the caller, came from
  // consecutive lines (at most block_lines) starting with line number `line` at line_start.
  void added_lines(std::size_t first, std::int64_t line, const char* line_start, bool session_start) {
    blocks_.push_back({first, line, line_start, session_start});
  }

  // Where sample i came from.
  std::int64_t line(std::size_t i) const;
  std::string_view text(std::size_t i) const;  // the line without its terminator

  struct Block {
    std::size_t first;          // index of its first sample
    std::int64_t first_line;    // that sample's line number
    const char* start;          // that line's first byte
    bool session_start;         // its first sample is the first of a logging session
  };
  const std::vector<Block>& blocks() const { return blocks_; }

 private:
  const Block& block_of(std::size_t i) const;
  std::vector<Block> blocks_;
  const char* text_end_;
};

// A person's name written on a line of its own between a recording's samples: a name typed into
// the serial monitor's send box and echoed by the sketch ("Ben"), a comment ("# Dmitri run 1",
// "--- Chloé, 2nd try ---", "// Ben"), a spreadsheet row of the name alone ("Jürgen;"). The name:
// up to three capitalised words of letters (any script), before "run", a number or a comma. None
// for a column header, a number, a boot message or a word a device prints ("Ready", "Start").
std::optional<std::string> written_name(std::string_view line);

struct TimelineRules {
  double units_per_s = 1000;      // 1000 for ms
  std::string_view unit = "ms";   // for messages
  double wrap = 0;                // counter modulus in file units (2^32 for millis()); 0 = none
  double reset_min_back = 1000;   // a jump back larger than this, confirmed by the next
                                  // sample, is a device restart (file units)
  bool drop_cut_first = true;     // a session's first sample off the cadence was cut short
};

struct TimelineCounts {
  std::size_t cut_first = 0, backwards = 0, ahead = 0, duplicates = 0, wraps = 0, restarts = 0,
              gaps = 0;
  std::size_t dropped() const { return cut_first + backwards + ahead + duplicates; }
};

// Appends the usable samples to rec (t_s = unwrapped t / units_per_s) and says what it did
// about every sample it did not use and every wrap, restart and gap. Takes raw's arrays: the
// samples kept are moved down in place and handed to rec, with no copy when rec was empty.
TimelineCounts build_timeline(RawSamples& raw, const TimelineRules& rules, Recording& rec, LineReporter& reporter);

// A reader's summary: head, then ", N what" for every count that is not zero, in order, then
// the timeline's (cut first line, time going back, …, clock wrap).
struct Count {
  std::size_t n;
  std::string_view what;
};
std::string summary_with_counts(std::string head, std::initializer_list<Count> counts, const TimelineCounts& timeline);

// The checks every text reader makes before it reads a line: its options, an empty file, an office
// document (an Excel workbook: "save it as CSV (UTF-8)") and (unless the reader decides that itself
// on its fast path, binary_check false) bytes that are not text.
// False when rec now holds the error; `what` names what the reader expected ("delimited text").
template <class Options>
bool readable_text(std::string_view text, const Options& options, std::string_view what, Recording& rec,
                   bool binary_check = true) {
  std::string why;
  if (!options.is_valid(&why)) {
    rec.error(0, "invalid reader options: " + why);
    return false;
  }
  if (text.empty()) {
    rec.error(0, "no samples: the file is empty");
    return false;
  }
  if (const auto office = office_document(text)) {
    rec.error(0, "no samples: " + *office);
    return false;
  }
  std::size_t control = 0, looked_at = 0;
  if (binary_check && looks_binary(text, &control, &looked_at)) {
    rec.error(0, binary_data_error(what, control, looked_at));
    return false;
  }
  return true;
}

// A reader's *_file variant: the file's bytes, or a Recording holding why they could not be read.
template <class Options, class Reader>
Recording read_text_file(const std::string& path, const Options& options, Reader&& read) {
  std::string why;
  auto bytes = read_file_bytes(path, &why);
  if (!bytes) {
    Recording rec;
    rec.source = path;
    rec.error(0, why);
    return rec;
  }
  return read(*bytes, path, options);
}

}  // namespace spindown::text
