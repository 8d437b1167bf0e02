#pragma once
// One line of delimited text into its fields, as RFC 4180 reads them: a field in double quotes
// may hold the delimiter ("RR_Wheel,Speed", "Schäfer, Jana") and "" for a quote; blanks around a
// field are dropped, blanks inside quotes kept. A delimiter of ' ' means any run of blanks (space
// or tab). One splitter for every delimited text spindown reads (recordings, rosters); the CSV it
// writes is csv_cells.hpp's.
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

class CsvFieldSplitter {
 public:
  // Fields of line into out (cleared first). The views point into line, or into this splitter
  // for a field that held "" (valid until the next split). A line without a quote costs no copy.
  void split(std::string_view line, char delimiter, std::vector<std::string_view>& out);
  // The last split's line ended inside quotes (its last field is the rest of the line).
  bool open_quote() const { return open_quote_; }

 private:
  std::string unquoted_;
  bool open_quote_ = false;
};

}  // namespace spindown
