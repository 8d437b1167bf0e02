// text_encoding.hpp: the bytes Windows tools and spreadsheets write, decoded to UTF-8 — real bytes
// as Excel and Notepad save them (cp1252 with ';' and CR LF, UTF-16LE with a byte-order mark, a
// UTF-8 mark), a trailing Ctrl-Z, and office documents named as such.
#include <gtest/gtest.h>

#include <string>

#include "spindown/text_encoding.hpp"

using namespace spindown;

namespace {

std::string bytes(std::initializer_list<int> b) {
  std::string s;
  for (int c : b) s += static_cast<char>(c);
  return s;
}

// A German Excel's "CSV (Trennzeichen-getrennt)": "Björn Schäfer", "Müller, Jürgen", "Anna Weiß",
// "Renée" in Windows-1252, ';', CR LF, the empty rows Excel keeps as ';;'.
const std::string excel_cp1252 = "file;bench;student\r\n"
                                 "schaefer.txt;bench3;Bj\xF6rn Sch\xE4" "fer\r\n"
                                 "mueller.txt;bench1;M\xFCller, J\xFCrgen\r\n"
                                 "weiss.txt;bench2;Anna Wei\xDF\r\n"
                                 "dubois.txt;bench4;Ren\xE9" "e Dubois \x80 \x96\r\n"
                                 ";;\r\n;;\r\n";

}  // namespace

TEST(TextEncoding, AsciiAndUtf8AreLeftAlone) {
  const EncodingGuess ascii = guess_text_encoding("0\t0.00\r\n20\t2.45\r\n");
  EXPECT_EQ(ascii.encoding, TextEncoding::ascii);
  EXPECT_FALSE(needs_decoding(ascii));
  const EncodingGuess utf8 = guess_text_encoding("t [\xC2\xB5s],n [U/min]\nSch\xC3\xA4" "fer\n");
  EXPECT_EQ(utf8.encoding, TextEncoding::utf8);
  EXPECT_FALSE(needs_decoding(utf8));
  EXPECT_TRUE(decoding_note(utf8).empty());
}

TEST(TextEncoding, Windows1252FromAGermanExcel) {
  const EncodingGuess g = guess_text_encoding(excel_cp1252);
  EXPECT_EQ(g.encoding, TextEncoding::cp1252);
  EXPECT_EQ(g.not_utf8, 8u);
  ASSERT_TRUE(needs_decoding(g));
  const std::string text = decode_text(excel_cp1252, g);
  EXPECT_NE(text.find("Bj\xC3\xB6rn Sch\xC3\xA4" "fer"), std::string::npos) << text;
  EXPECT_NE(text.find("M\xC3\xBCller, J\xC3\xBCrgen"), std::string::npos);
  EXPECT_NE(text.find("Anna Wei\xC3\x9F"), std::string::npos);
  // 0x80 is the euro sign and 0x96 an en dash in Windows-1252 (not Latin-1's C1 controls).
  EXPECT_NE(text.find("Ren\xC3\xA9" "e Dubois \xE2\x82\xAC \xE2\x80\x93\r\n"), std::string::npos);
  EXPECT_NE(text.find(";;\r\n;;\r\n"), std::string::npos);  // lines stay where they were
  EXPECT_NE(decoding_note(g).find("Windows-1252"), std::string::npos) << decoding_note(g);
  // Excel's µ (0xB5) in a unit.
  EXPECT_EQ(decode_text("t [\xB5s]", guess_text_encoding("t [\xB5s]")), "t [\xC2\xB5s]");
}

TEST(TextEncoding, Utf16LittleEndianWithAMarkAsExcelsUnicodeText) {
  // "file\tstudent\r\nweiss.txt\tAnna Weiß\r\n" as Excel's "Unicode Text (*.txt)" saves it.
  std::string utf16 = bytes({0xFF, 0xFE});
  for (char16_t c : std::u16string(u"file\tstudent\r\nweiss.txt\tAnna Wei\u00DF\r\n")) {
    utf16 += static_cast<char>(c & 0xFF);
    utf16 += static_cast<char>(c >> 8);
  }
  const EncodingGuess g = guess_text_encoding(utf16);
  EXPECT_EQ(g.encoding, TextEncoding::utf16le);
  EXPECT_TRUE(g.bom);
  EXPECT_EQ(decode_text(utf16, g), "file\tstudent\r\nweiss.txt\tAnna Wei\xC3\x9F\r\n");
  EXPECT_NE(decoding_note(g).find("UTF-16"), std::string::npos);
}

TEST(TextEncoding, Utf8ByteOrderMarkIsDropped) {
  const std::string text = "\xEF\xBB\xBF" "file,bench,student\r\nw.txt,b1,Anna Wei\xC3\x9F\r\n";
  const EncodingGuess g = guess_text_encoding(text);
  EXPECT_EQ(g.encoding, TextEncoding::utf8_bom);
  EXPECT_EQ(decode_text(text, g), "file,bench,student\r\nw.txt,b1,Anna Wei\xC3\x9F\r\n");
}

TEST(TextEncoding, MixedTextIsLeftAsItIs) {
  // UTF-8 with one line of serial noise: not re-read as Windows-1252 (that would garble the µ).
  const std::string text = "t [\xC2\xB5s]\tV\n0\t0.00\n\xFF\xFE\xC3(\t\xA0\n";
  const EncodingGuess g = guess_text_encoding(text);
  EXPECT_EQ(g.encoding, TextEncoding::mixed);
  EXPECT_EQ(g.not_utf8, 4u);
  EXPECT_FALSE(needs_decoding(g));
}

TEST(TextEncoding, ATrailingCtrlZIsTheEndOfTheText) {
  const std::string lab = "0\t0.00\r\n20\t2.45\r\n";
  for (const std::string& tail : {std::string("\x1A"), std::string("\x1A\r\n"), std::string("\x1A\x1A")}) {
    const EncodingGuess g = guess_text_encoding(lab + tail);
    EXPECT_EQ(g.dos_eof, tail.size());
    EXPECT_TRUE(needs_decoding(g));
    EXPECT_EQ(decode_text(lab + tail, g), lab);
    EXPECT_TRUE(decoding_note(g).empty());  // silently: it is only the DOS end-of-file mark
  }
  // A Ctrl-Z inside the text (serial noise) is not an end.
  EXPECT_EQ(guess_text_encoding("0\t0.00\x1A\r\n20\t2.45\r\n").dos_eof, 0u);
  // Windows-1252 and a Ctrl-Z together.
  const std::string both = "Zeit;Spannung [\xB5V]\r\n\x1A";
  EXPECT_EQ(decode_text(both, guess_text_encoding(both)), "Zeit;Spannung [\xC2\xB5V]\r\n");
}

TEST(TextEncoding, OfficeDocumentsAreNamedWithWhatToDo) {
  // An .xlsx as Excel writes it: a zip whose first entry is [Content_Types].xml.
  const std::string xlsx = bytes({0x50, 0x4B, 0x03, 0x04, 0x14, 0x00, 0x06, 0x00, 0x08, 0x00, 0x00, 0x00, 0x21, 0x00,
                                  0x62, 0xEE, 0x9D, 0x68, 0x5E, 0x01, 0x00, 0x00, 0x90, 0x04, 0x00, 0x00, 0x13, 0x00,
                                  0x08, 0x02}) +
                           "[Content_Types].xml" + bytes({0xA2, 0x04, 0x02, 0x28, 0xA0, 0x00, 0x02});
  const auto x = office_document(xlsx);
  ASSERT_TRUE(x);
  EXPECT_NE(x->find("an Excel workbook (.xlsx)"), std::string::npos) << *x;
  EXPECT_NE(x->find("save it as CSV (UTF-8)"), std::string::npos) << *x;
  EXPECT_EQ(x->find("binary"), std::string::npos);
  // An .xls (Excel 97-2003): an OLE compound file.
  const std::string xls = bytes({0xD0, 0xCF, 0x11, 0xE0, 0xA1, 0xB1, 0x1A, 0xE1, 0, 0, 0, 0, 0, 0, 0, 0});
  ASSERT_TRUE(office_document(xls));
  EXPECT_NE(office_document(xls)->find("an Excel workbook (.xls)"), std::string::npos);
  // LibreOffice's .ods: its first entry is the uncompressed mimetype.
  const std::string ods = "PK\x03\x04" + std::string(26, '\0') + "mimetypeapplication/vnd.oasis.opendocument.spreadsheet";
  EXPECT_NE(office_document(ods)->find("OpenDocument spreadsheet"), std::string::npos);
  EXPECT_NE(office_document("PK\x03\x04" + std::string(26, '\0') + "data/run1.txt")->find("zip archive"),
            std::string::npos);
  EXPECT_FALSE(office_document("0\t0.00\r\n"));
  EXPECT_FALSE(office_document("PK"));
}

// Excel for Mac's "CSV (Comma delimited)": Mac OS Roman, lines ended by a CR alone. The names
// come out right (ë is 0x91 there, a quotation mark in Windows-1252), and the note says so.
TEST(TextEncoding, ExcelForMacCsvIsMacRoman) {
  const std::string bytes = "file,bench,student\rZo\x91/putty.log,bench1,Zo\x91 Bront\x91\rJ\x9Fgen,bench2,J\x9Frgen Gro\xA7\r";
  const EncodingGuess g = guess_text_encoding(bytes);
  EXPECT_EQ(g.encoding, TextEncoding::mac_roman);
  const std::string text = decode_text(bytes, g);
  EXPECT_NE(text.find("Zo\xC3\xAB Bront\xC3\xAB"), std::string::npos) << text;
  EXPECT_NE(text.find("J\xC3\xBCrgen Gro\xC3\x9F"), std::string::npos) << text;
  EXPECT_NE(decoding_note(g).find("Mac OS Roman"), std::string::npos);
  // The same bytes with Windows line ends are Windows-1252.
  EXPECT_EQ(guess_text_encoding("a,b\r\nZo\x91,1\r\n").encoding, TextEncoding::cp1252);
}
