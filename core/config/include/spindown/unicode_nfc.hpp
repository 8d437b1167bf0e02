#pragma once
// Names compared as a person reads them, not as bytes: "Jürgen" typed on Linux or Windows is one
// code point ü (NFC); a folder unzipped on a Mac, or a name copied from Finder, spells it u and a
// combining diaeresis (NFD). Rosters, folders and file names are compared after NFC (Unicode
// normalisation, utf8proc).
#include <string>
#include <string_view>

namespace spindown {

// text in NFC; text as it is when it is not valid UTF-8 (bytes compared as they are).
std::string nfc(std::string_view text);

}  // namespace spindown
