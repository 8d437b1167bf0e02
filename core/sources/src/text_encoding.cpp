#include "spindown/text_encoding.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>

#include "spindown/text_support.hpp"

namespace spindown {

namespace {

// The first byte above 0x7F in [from, size), or size: 8 bytes at a time (a lab file is ASCII).
std::size_t first_high_byte(std::string_view s, std::size_t from) {
  std::size_t i = from;
  for (; i + sizeof(std::uint64_t) <= s.size(); i += sizeof(std::uint64_t)) {
    std::uint64_t w;
    std::memcpy(&w, s.data() + i, sizeof w);
    if (w & 0x8080808080808080ull) break;
  }
  for (; i < s.size(); ++i)
    if (static_cast<unsigned char>(s[i]) >= 0x80) return i;
  return s.size();
}

// A byte-order mark, or (no mark) ASCII text every other byte of which is NUL.
TextEncoding utf16_kind(std::string_view text, bool* has_bom) {
  *has_bom = false;
  if (text.size() >= 2) {
    const auto b0 = static_cast<unsigned char>(text[0]), b1 = static_cast<unsigned char>(text[1]);
    if (b0 == 0xFF && b1 == 0xFE) return *has_bom = true, TextEncoding::utf16le;
    if (b0 == 0xFE && b1 == 0xFF) return *has_bom = true, TextEncoding::utf16be;
  }
  const std::size_t n = std::min(text.size(), std::size_t{512}) & ~std::size_t{1};
  if (n < 16) return TextEncoding::ascii;
  std::size_t even_nul = 0, odd_nul = 0;
  for (std::size_t i = 0; i < n; i += 2) {
    even_nul += text[i] == '\0';
    odd_nul += text[i + 1] == '\0';
  }
  const std::size_t pairs = n / 2;
  if (odd_nul * 10 >= pairs * 9 && even_nul * 20 <= pairs) return TextEncoding::utf16le;
  if (even_nul * 10 >= pairs * 9 && odd_nul * 20 <= pairs) return TextEncoding::utf16be;
  return TextEncoding::ascii;
}

void append_utf8(std::string& out, std::uint32_t cp) {
  if (cp < 0x80) {
    out += static_cast<char>(cp);
  } else if (cp < 0x800) {
    out += static_cast<char>(0xC0 | (cp >> 6));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += static_cast<char>(0xE0 | (cp >> 12));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  } else {
    out += static_cast<char>(0xF0 | (cp >> 18));
    out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
    out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
    out += static_cast<char>(0x80 | (cp & 0x3F));
  }
}

std::string utf16_to_utf8(std::string_view text, bool little_endian, bool skip_bom) {
  std::string out;
  out.reserve(text.size() / 2 + 16);
  const auto unit = [&](std::size_t i) -> std::uint32_t {
    const auto a = static_cast<unsigned char>(text[i]), b = static_cast<unsigned char>(text[i + 1]);
    return little_endian ? (std::uint32_t(b) << 8 | a) : (std::uint32_t(a) << 8 | b);
  };
  std::size_t i = skip_bom ? 2 : 0;
  for (; i + 1 < text.size(); i += 2) {
    const std::uint32_t u = unit(i);
    if (u >= 0xD800 && u <= 0xDBFF && i + 3 < text.size()) {
      const std::uint32_t lo = unit(i + 2);
      if (lo >= 0xDC00 && lo <= 0xDFFF) {
        append_utf8(out, 0x10000 + ((u - 0xD800) << 10) + (lo - 0xDC00));
        i += 2;
        continue;
      }
    }
    append_utf8(out, u >= 0xD800 && u <= 0xDFFF ? 0xFFFD : u);
  }
  if (i < text.size()) append_utf8(out, 0xFFFD);
  return out;
}

// Windows-1252's 0x80–0x9F; the five bytes it leaves undefined keep Latin-1's C1 controls, as
// Windows itself decodes them.
constexpr std::uint16_t cp1252_high[32] = {
    0x20AC, 0x0081, 0x201A, 0x0192, 0x201E, 0x2026, 0x2020, 0x2021, 0x02C6, 0x2030, 0x0160,
    0x2039, 0x0152, 0x008D, 0x017D, 0x008F, 0x0090, 0x2018, 0x2019, 0x201C, 0x201D, 0x2022,
    0x2013, 0x2014, 0x02DC, 0x2122, 0x0161, 0x203A, 0x0153, 0x009D, 0x017E, 0x0178};

// Mac OS Roman's 0x80–0xFF (Apple's table; 0xF0 is the Apple logo, a private-use character).
constexpr std::uint16_t mac_roman_high[128] = {
    0x00C4, 0x00C5, 0x00C7, 0x00C9, 0x00D1, 0x00D6, 0x00DC, 0x00E1, 0x00E0, 0x00E2, 0x00E4, 0x00E3, 0x00E5,
    0x00E7, 0x00E9, 0x00E8, 0x00EA, 0x00EB, 0x00ED, 0x00EC, 0x00EE, 0x00EF, 0x00F1, 0x00F3, 0x00F2, 0x00F4,
    0x00F6, 0x00F5, 0x00FA, 0x00F9, 0x00FB, 0x00FC, 0x2020, 0x00B0, 0x00A2, 0x00A3, 0x00A7, 0x2022, 0x00B6,
    0x00DF, 0x00AE, 0x00A9, 0x2122, 0x00B4, 0x00A8, 0x2260, 0x00C6, 0x00D8, 0x221E, 0x00B1, 0x2264, 0x2265,
    0x00A5, 0x00B5, 0x2202, 0x2211, 0x220F, 0x03C0, 0x222B, 0x00AA, 0x00BA, 0x03A9, 0x00E6, 0x00F8, 0x00BF,
    0x00A1, 0x00AC, 0x221A, 0x0192, 0x2248, 0x2206, 0x00AB, 0x00BB, 0x2026, 0x00A0, 0x00C0, 0x00C3, 0x00D5,
    0x0152, 0x0153, 0x2013, 0x2014, 0x201C, 0x201D, 0x2018, 0x2019, 0x00F7, 0x25CA, 0x00FF, 0x0178, 0x2044,
    0x20AC, 0x2039, 0x203A, 0xFB01, 0xFB02, 0x2021, 0x00B7, 0x201A, 0x201E, 0x2030, 0x00C2, 0x00CA, 0x00C1,
    0x00CB, 0x00C8, 0x00CD, 0x00CE, 0x00CF, 0x00CC, 0x00D3, 0x00D4, 0xF8FF, 0x00D2, 0x00DA, 0x00DB, 0x00D9,
    0x0131, 0x02C6, 0x02DC, 0x00AF, 0x02D8, 0x02D9, 0x02DA, 0x00B8, 0x02DD, 0x02DB, 0x02C7};

std::string single_byte_to_utf8(std::string_view text, bool mac) {
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t high = first_high_byte(text, i);
    out.append(text.substr(i, high - i));
    if (high == text.size()) break;
    const auto c = static_cast<unsigned char>(text[high]);
    append_utf8(out, mac ? mac_roman_high[c - 0x80] : c < 0xA0 ? cp1252_high[c - 0x80] : c);
    i = high + 1;
  }
  return out;
}

// Lines ended by a CR alone (a classic Mac's, as Excel for Mac writes CSV), none by LF.
bool cr_line_ends(std::string_view s) { return s.find('\r') != std::string_view::npos && s.find('\n') == std::string_view::npos; }

// Trailing Ctrl-Z: from the first 0x1A of a run at the end (line ends between them allowed).
std::size_t dos_eof_bytes(std::string_view s) {
  std::size_t end = s.size();
  std::size_t cut = s.size();
  while (end > 0) {
    const char c = s[end - 1];
    if (c == '\x1A') cut = end - 1;
    else if (c != '\r' && c != '\n') break;
    --end;
  }
  return s.size() - cut;
}

bool contains(std::string_view hay, std::string_view needle) { return hay.find(needle) != std::string_view::npos; }

}  // namespace

EncodingGuess guess_text_encoding(std::string_view bytes) {
  EncodingGuess g;
  bool bom = false;
  const TextEncoding wide = utf16_kind(bytes, &bom);
  if (wide != TextEncoding::ascii) {
    g.encoding = wide;
    g.bom = bom;
    return g;
  }
  g.dos_eof = dos_eof_bytes(bytes);
  bytes.remove_suffix(g.dos_eof);
  if (bytes.starts_with("\xEF\xBB\xBF")) {
    g.bom = true;
    g.encoding = TextEncoding::utf8_bom;
    bytes.remove_prefix(3);
  }
  std::size_t multibyte = 0;
  for (std::size_t i = first_high_byte(bytes, 0); i < bytes.size(); i = first_high_byte(bytes, i)) {
    const std::size_t len = text::utf8_sequence_length(bytes, i);
    if (len == 0) {
      ++g.not_utf8;
      ++i;
    } else {
      ++multibyte;
      i += len;
    }
  }
  if (g.not_utf8 > 0)
    g.encoding = multibyte > 0 || g.bom ? TextEncoding::mixed
                 : cr_line_ends(bytes)  ? TextEncoding::mac_roman
                                        : TextEncoding::cp1252;
  else if (multibyte > 0 && !g.bom) g.encoding = TextEncoding::utf8;
  return g;
}

bool needs_decoding(const EncodingGuess& g) {
  return g.dos_eof > 0 || g.bom || g.encoding == TextEncoding::cp1252 || g.encoding == TextEncoding::mac_roman ||
         g.encoding == TextEncoding::utf16le ||
         g.encoding == TextEncoding::utf16be;
}

std::string decode_text(std::string_view bytes, const EncodingGuess& g) {
  if (g.encoding == TextEncoding::utf16le || g.encoding == TextEncoding::utf16be) {
    std::string out = utf16_to_utf8(bytes, g.encoding == TextEncoding::utf16le, g.bom);
    out.resize(out.size() - dos_eof_bytes(out));
    return out;
  }
  bytes.remove_suffix(g.dos_eof);
  if (g.bom && bytes.starts_with("\xEF\xBB\xBF")) bytes.remove_prefix(3);
  if (g.encoding == TextEncoding::cp1252 || g.encoding == TextEncoding::mac_roman)
    return single_byte_to_utf8(bytes, g.encoding == TextEncoding::mac_roman);
  return std::string(bytes);
}

std::string decoding_note(const EncodingGuess& g) {
  switch (g.encoding) {
    case TextEncoding::utf16le:
    case TextEncoding::utf16be:
      return fmt::format("read as UTF-16 ({}{}), as Excel saves \"Unicode text\" and a Windows editor \"Unicode\"",
                         g.encoding == TextEncoding::utf16le ? "little-endian" : "big-endian",
                         g.bom ? ", with a byte-order mark" : ", no byte-order mark");
    case TextEncoding::cp1252:
      return fmt::format("read as Windows-1252 (cp1252, Latin-1), as Excel saves \"CSV\" on a Western European PC: "
                         "{} byte{} {} not UTF-8; save as \"CSV UTF-8\" to be sure of every character",
                         g.not_utf8, g.not_utf8 == 1 ? "" : "s", g.not_utf8 == 1 ? "is" : "are");
    case TextEncoding::mac_roman:
      return fmt::format("read as Mac OS Roman, as Excel for Mac saves \"CSV\" (lines end in CR alone): {} byte{} "
                         "{} not UTF-8; save as \"CSV UTF-8\" to be sure of every character",
                         g.not_utf8, g.not_utf8 == 1 ? "" : "s", g.not_utf8 == 1 ? "is" : "are");
    case TextEncoding::utf8_bom: return "UTF-8 byte-order mark skipped";
    case TextEncoding::ascii:
    case TextEncoding::utf8:
    case TextEncoding::mixed: break;
  }
  return {};
}

std::optional<std::string> office_document(std::string_view bytes) {
  constexpr std::string_view save_as =
      "open it in Excel (or LibreOffice Calc) and save it as CSV (UTF-8): File > Save As > \"CSV UTF-8 (Comma "
      "delimited) (*.csv)\"";
  if (bytes.starts_with("PK\x03\x04")) {
    // A zip archive: its entries' names are stored uncompressed in their headers.
    if (contains(bytes.substr(0, 256), "mimetypeapplication/vnd.oasis.opendocument.spreadsheet"))
      return fmt::format("an OpenDocument spreadsheet (.ods), not a text file: {}", save_as);
    if (contains(bytes, "word/document.xml"))
      return "a Word document (.docx), not a text file: copy the numbers into a plain text file, or hand in the "
             "recording itself (a PuTTY log, a CSV)";
    // An Office Open XML package: its first entry is [Content_Types].xml; a hand-in is a workbook.
    if (contains(bytes, "xl/workbook.xml") || contains(bytes, "xl/worksheets/") ||
        contains(bytes.substr(0, 64), "[Content_Types].xml"))
      return fmt::format("an Excel workbook (.xlsx), not a text file: {}", save_as);
    return std::string("a zip archive, not a text file: unpack it and give the recording inside");
  }
  if (bytes.starts_with("\xD0\xCF\x11\xE0\xA1\xB1\x1A\xE1")) {
    // An OLE compound file: Excel 97–2003 names its stream "Workbook" (UTF-16LE), Word "WordDocument".
    if (contains(bytes, std::string_view("W\0o\0r\0d\0D\0o\0c\0u\0m\0e\0n\0t\0", 24)))
      return "a Word document (.doc), not a text file: copy the numbers into a plain text file, or hand in the "
             "recording itself (a PuTTY log, a CSV)";
    return fmt::format("an Excel workbook (.xls), not a text file: {}", save_as);
  }
  return std::nullopt;
}

}  // namespace spindown
