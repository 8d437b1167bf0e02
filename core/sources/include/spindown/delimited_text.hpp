#pragma once
// Delimited text with a time column and a value column: CSV, semicolon CSV (decimal comma
// allowed), TSV or whitespace-separated, with or without a header row; fields in double quotes
// as RFC 4180 has them ("RR_Wheel,Speed" is one name). The user names the columns and units when
// they are not obvious; otherwise they are detected from the header's names and units in the
// spellings column_names.hpp reads ("millis", "time_ms", "Drehzahl [U/min]", "omega (rad/s)",
// "Voltage [mV]", a row of units under the names), and a clear error says what is ambiguous: a
// unit the header gives that spindown cannot read names the --value-unit to give, a table without
// names proposes its time and speed columns from the numbers (column_guess.hpp). Rows of
// separators alone (";;;;", a spreadsheet's empty rows) are blank.
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/csv_fields.hpp"
#include "spindown/column_names.hpp"
#include "spindown/quantity.hpp"
#include "spindown/recording.hpp"

namespace spindown {

struct DelimitedTextOptions {
  // Column by header name (case-insensitive; "time" also matches "time (s)") or 1-based
  // index ("2"). Empty: detect.
  std::string time_column;
  std::string value_column;
  std::optional<TimeUnit> time_unit;  // empty: from the header, else from the data (a note says so)
  std::optional<Quantity> quantity;   // empty: from the header, else volts without a header
  double value_scale = 1;             // with quantity: a reading times this is in it (mV: 0.001)
  char delimiter = 0;                 // ',', ';', '\t' or ' ' (any run of blanks); 0: detect
  std::optional<bool> header;         // empty: a first row with a non-number is a header
  // The readings' period (ms) when the file has no time column (a sketch that prints the volts
  // alone at a known rate, delay(20)): row k's time is k periods; a time column is not read.
  std::optional<double> period_ms;
  std::size_t max_line_reports = 20;  // bad lines reported one by one before only a count

  // True when the user named anything about the columns (then a text file is read as
  // delimited text, not as Arduino text).
  bool names_columns() const;
  bool is_valid(std::string* why) const;
};

// Whether a file whose first line with content is `line` must be read as delimited text for its
// header to be honoured: a header row (no field a number) in any delimiter that gives a value unit
// other than volts (rpm, U/min, rad/s, mV, …), a time unit other than ms, a unit spindown cannot
// read, or names a speed without a unit. The lab's own "millis<TAB>volts" does not.
bool header_needs_delimited_reader(std::string_view line);

// The layout a delimited text was read by: what read_delimited_text chose or was told, enough to
// read one more row of it alone. The serial bridge reads a sketch's lines with it (learned by
// read_delimited_text from the first lines), so what `spindown fit` reads of a capture is what the
// bridge publishes of the same bytes.
struct DelimitedLayout {
  char delimiter = '\t';       // ',', ';', '\t' or ' ' (any run of blanks)
  bool decimal_comma = false;  // "2,81" is 2.81
  int time_column = 0;         // 0-based
  int value_column = 1;
  TimeUnit time_unit = TimeUnit::ms;
  Quantity quantity = Quantity::back_emf_volts;
  bool quantity_from_header = false;  // false: assumed (volts) or given
  double value_scale = 1;             // a reading times this is in quantity
};

// One row by a layout: its time (in the layout's time unit) and value (in its quantity), or why
// not ("3 fields, column 4 is missing", "time 'x' is not a number"). read_delimited_text reads
// every row of a file with it.
class DelimitedRowReader {
 public:
  explicit DelimitedRowReader(const DelimitedLayout& layout) : layout_(layout) {}
  struct Row {
    bool ok = false;
    double time = 0, value = 0;
    std::string why;
  };
  Row read(std::string_view line);
  // The fields of line (single quotes taken off), valid until the next call.
  const std::vector<std::string_view>& split(std::string_view line, char delimiter);
  const DelimitedLayout& layout() const { return layout_; }
  void set_time_unit(TimeUnit unit) { layout_.time_unit = unit; }

 private:
  DelimitedLayout layout_;
  CsvFieldSplitter splitter_;
  std::vector<std::string_view> fields_;
};

// Reads text; when layout is given, it is set to the layout the rows were read by (when there
// were rows to read).
Recording read_delimited_text(std::string_view text, std::string source, const DelimitedTextOptions& options = {},
                              DelimitedLayout* layout = nullptr);
Recording read_delimited_text_file(const std::string& path, const DelimitedTextOptions& options = {});

}  // namespace spindown
