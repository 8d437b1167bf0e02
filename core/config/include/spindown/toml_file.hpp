#pragma once
// Reading a TOML file (bench files, bridge settings) with errors that name the file, line and
// column, the way every other reader in spindown reports bad input.
#include <string>
#include <toml++/toml.h>

namespace spindown {

// The parsed file. Throws std::runtime_error "PATH: cannot read: …" when it is not a readable
// file, "PATH:LINE:COLUMN: what is wrong" when it is not TOML.
toml::table parse_toml_file(const std::string& path);

}  // namespace spindown
