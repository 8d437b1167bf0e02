#pragma once
// What students' editors and terminals do to the lab's text, undone before it is read. Each
// repair keeps every line where it was (diagnostics still name the right line) and is said in a
// note:
//  - the encoding: UTF-16, Windows-1252, a byte-order mark, a trailing Ctrl-Z (text_encoding.hpp),
//    decoded to UTF-8 (binary data and office documents are left to the readers, which refuse them);
//  - the Arduino IDE serial monitor's timestamps ("10:21:38.234 -> 5234<TAB>0.00"): removed, the
//    sample's own millis stays its time;
//  - the Serial Plotter's labelled values ("millis:2020,volts:0.00"): a header of the labels and
//    the values beneath it;
//  - a pyserial script's print(ser.readline()): Python bytes literals (b'5234\t2.80\r\n'),
//    unwrapped and unescaped;
//  - a decimal comma in the lab's two columns ("5234<TAB>2,45", a spreadsheet with a European
//    locale): read as a point, only when no sample line uses a point.
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

// The Arduino IDE Serial Plotter's labelled values, "millis:2020,volts:0.00" (fields separated by
// commas, tabs or spaces, each "label:number"): the values alone, comma-separated, into *values
// and the labels (comma-separated) into *labels. False when line is not such a line.
bool plotter_labels(std::string_view line, std::string* labels, std::string* values);

// Whether repair_text would change text (its first lines, and the whole text for bytes above 0x7F; cheap).
bool needs_text_repair(std::string_view text);

// Rewrites text in place; returns one note per repair made (empty: nothing to do).
std::vector<std::string> repair_text(std::string& text);

}  // namespace spindown
