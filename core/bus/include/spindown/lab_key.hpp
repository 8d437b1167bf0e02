#pragma once
// The lab key: 32 secret bytes every lab PC's services share; bridges sign their SAMPLE, CONFIG
// and STATUS with it, the fitter its RUN, FIT, EXPLAIN and STATUS, and every reader verifies
// (message_auth.hpp, docs/security.md). The key lives in a file only the services read:
// systemd's LoadCredential=lab-key:/etc/spindown/lab.key hands it to each unit in
// $CREDENTIALS_DIRECTORY, and programs run by hand take --key FILE.
//
// The file holds the 32 bytes as they are (`spindown keygen -o FILE`, or
// `head -c 32 /dev/urandom > FILE`), or as 64 hex digits (a trailing newline allowed).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace spindown {

inline constexpr std::size_t lab_key_bytes = 32;
// The name of the credential the units load (LoadCredential=lab-key:…).
inline constexpr const char* lab_key_credential = "lab-key";
inline constexpr const char* lab_key_previous_credential = "lab-key-previous";

struct LabKey {
  std::array<unsigned char, lab_key_bytes> bytes{};
  // The key's id, sent with every signed message so a reader with another key says so (not the
  // key itself: the first 4 bytes of BLAKE2b of a label and the key). Never 0 (0 = not signed).
  std::int32_t id = 0;
  std::string path;      // where it was read from
  std::string warning;   // e.g. the file is readable by other users ("" when none)
};

// The key in a file; nullopt and *why (naming the file and what is wrong) otherwise.
std::optional<LabKey> load_lab_key(const std::string& path, std::string* why = nullptr);
// A key from its 32 bytes (tests, and load_lab_key).
LabKey lab_key_from_bytes(const std::array<unsigned char, lab_key_bytes>& bytes);

// The key a program uses: option_path when not empty, else the credential lab-key in
// credentials_dir ($CREDENTIALS_DIRECTORY under systemd) when that file exists, else none
// (signing off). error is set when a key was asked for (or present) but cannot be used.
// While keys are changed (docs/security.md, "Changing the key"), option_path may name several
// files, comma-separated: the first signs, every one is accepted; under systemd the credential
// lab-key-previous, when present, is accepted too.
struct LabKeyChoice {
  std::optional<LabKey> key;
  std::vector<LabKey> also_accepted;  // keys accepted besides key (a rotation)
  std::string source;  // "--key FILE", "systemd credential lab-key", "" (none)
  std::string error;
};
LabKeyChoice choose_lab_key(const std::string& option_path, const std::optional<std::string>& credentials_dir);
// The same with $CREDENTIALS_DIRECTORY from the environment.
LabKeyChoice choose_lab_key(const std::string& option_path);

// `spindown keygen`: 32 random bytes into a new file (mode 0600; never overwrites one that
// exists). False and *why otherwise.
bool write_new_lab_key(const std::string& path, std::string* why = nullptr);

// "0x1f2e3d4c": a key id as messages and tables print it.
std::string key_id_text(std::int32_t id);

}  // namespace spindown
