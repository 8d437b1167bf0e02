#pragma once
// One internal representation of measured data, whatever the source (Arduino text,
// delimited text, LCM log): device time in seconds on the source's own clock, a value
// and its quantity, plus every problem met while reading it.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "spindown/quantity.hpp"

namespace spindown {

// A problem found in the input, with where it was (line number for text, event number
// for logs; 0 when it concerns the whole source).
struct Diagnostic {
  enum class Severity { note, warning, error };
  Severity severity = Severity::warning;
  std::string source;     // file name or channel
  std::int64_t line = 0;  // 1-based line (or log event) number, 0 = whole source
  std::string message;    // what was wrong and what was done about it
  std::string to_string() const;  // "file:line: warning: message"
};

struct Recording {
  std::string source;
  Quantity quantity = Quantity::back_emf_volts;
  std::vector<double> t_s;    // device time (s), the source's own clock
  std::vector<double> value;  // in quantity's unit
  // Indices where the device clock restarted (Arduino reset): a run never spans one.
  std::vector<std::size_t> clock_restarts;
  std::vector<Diagnostic> diagnostics;
  // Names written between the samples (a student's name typed into the serial monitor and echoed,
  // a comment "# Dmitri run 1", a spreadsheet row "Jürgen;"): each with the index of the first
  // sample after it. A run belongs to the last name written before its cut.
  struct Name {
    std::size_t sample;
    std::string name;
    std::int64_t line;
  };
  std::vector<Name> names;
  // The name written last before sample index i ("" when none).
  std::string name_before(std::size_t i) const {
    std::string out;
    for (const Name& n : names)
      if (n.sample <= i) out = n.name;
    return out;
  }
  std::size_t lines_read = 0;     // lines (or events) looked at
  std::size_t lines_skipped = 0;  // of those, not used as samples (blank, garbled, header…)

  std::size_t size() const { return t_s.size(); }
  bool empty() const { return t_s.empty(); }
  void push(double t, double v) {
    t_s.push_back(t);
    value.push_back(v);
  }
  void warn(std::int64_t line, std::string message);
  void note(std::int64_t line, std::string message);
  void error(std::int64_t line, std::string message);
  bool has_errors() const;
};

}  // namespace spindown
