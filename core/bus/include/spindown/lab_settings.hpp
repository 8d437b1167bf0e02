#pragma once
// --lab NAME and --key FILE, as every program that sends or reads the lab's messages takes them
// (issue 31): the lab's name (lab_name.hpp: the option, else $SPINDOWN_LAB, else "lab") and the
// lab key (lab_key.hpp: the option, else the systemd credential lab-key, else none: messages are
// not signed and signatures not required).
#include <optional>
#include <string>
#include <vector>

#include "spindown/lab_key.hpp"

namespace spindown {

struct LabSettings {
  std::string lab;
  std::optional<LabKey> key;
  std::vector<LabKey> also_accepted;  // accepted besides key while keys are changed
  std::string key_source;  // where the key came from ("" without one)
};

// nullopt and *why (naming the option, the variable or the file) when the name is not valid or a
// key was given (or loaded by systemd) but cannot be read.
std::optional<LabSettings> resolve_lab_settings(const std::string& lab_option, const std::string& key_option,
                                                std::string* why = nullptr);

// "lab 'physics-1'; messages signed with key 0x1f2e3d4c (systemd credential lab-key)", or
// "lab 'lab'; messages not signed (no lab key)".
std::string lab_settings_text(const LabSettings& s);

// The option texts every program's --help shows for them.
inline constexpr const char* lab_option_help =
    "lab name: only this lab's messages are used, and every message sent names it (default: $SPINDOWN_LAB, else "
    "'lab')";
inline constexpr const char* key_option_help =
    "lab key file (32 bytes; spindown keygen): sign what is sent and use only messages signed with it (default: "
    "the systemd credential lab-key when the unit loads one; none: signing off); NEW,OLD while keys change: signs "
    "with NEW, accepts both (docs/security.md)";

}  // namespace spindown
