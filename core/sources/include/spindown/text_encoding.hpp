#pragma once
// The bytes of a text file as Windows tools and spreadsheets write them, decoded to the UTF-8
// every reader and every output works in:
//  - UTF-8, with or without a byte-order mark (Excel's "CSV UTF-8" writes one): the mark dropped;
//  - UTF-16 with or without a byte-order mark (Excel's "Unicode text", Notepad's "Unicode");
//  - Windows-1252 (cp1252, a superset of Latin-1's printable characters): what Excel's "CSV"
//    and "CSV (Trennzeichen-getrennt)" and older Windows editors write on a Western European PC.
//    Taken when bytes above 0x7F occur and none of them forms UTF-8; text that mixes UTF-8 with
//    bytes that are not is left alone (its bad bytes are shown as \xNN where a message quotes them);
//  - Mac OS Roman: what Excel for Mac's "CSV (Comma delimited)" writes, its lines ended by a CR
//    alone (classic Mac). Taken instead of Windows-1252 when the lines end in CR only;
//  - a trailing Ctrl-Z (0x1A, DOS's end-of-file mark): the end of the text, without a word.
// An office document (an Excel workbook, .xlsx or .xls; an OpenDocument spreadsheet) is named as
// such, with what to do: save it as CSV (UTF-8).
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace spindown {

enum class TextEncoding { ascii, utf8, utf8_bom, utf16le, utf16be, cp1252, mac_roman, mixed };

struct EncodingGuess {
  TextEncoding encoding = TextEncoding::ascii;
  bool bom = false;              // a byte-order mark starts the text
  std::size_t not_utf8 = 0;      // bytes that are not part of a UTF-8 sequence (cp1252, mixed)
  std::size_t dos_eof = 0;       // trailing bytes from the first Ctrl-Z of the end on (0: none)
};

// What the bytes are; cheap for ASCII text (one pass looking for bytes above 0x7F).
EncodingGuess guess_text_encoding(std::string_view bytes);

// Whether decode_text would change the bytes.
bool needs_decoding(const EncodingGuess& guess);

// The text as UTF-8: the mark and the DOS end-of-file dropped, UTF-16 and cp1252 decoded (a lone
// surrogate, an odd last byte: U+FFFD). Lines stay where they were. ascii, utf8 and mixed text is
// returned as it is (less a Ctrl-Z).
std::string decode_text(std::string_view bytes, const EncodingGuess& guess);

// A note on what decode_text did ("read as Windows-1252 (cp1252) …"); empty for plain UTF-8/ASCII
// and for a Ctrl-Z alone.
std::string decoding_note(const EncodingGuess& guess);

// When bytes are an office document rather than text: "an Excel workbook (.xlsx), not text: open
// it in Excel and save it as CSV UTF-8 (…)"; nullopt otherwise. Looks at the first bytes only.
std::optional<std::string> office_document(std::string_view bytes);

}  // namespace spindown
