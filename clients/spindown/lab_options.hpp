#pragma once
// --lab NAME and --key FILE for the commands that read the lab's messages (refit, export, fit and
// the other file commands on LCM logs, watch, doctor): one definition, so each takes them alike.
#include <string>

#include "spindown/lab_settings.hpp"
#include "spindown/message_gate.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct LabOptions {
  std::string lab;  // "" = $SPINDOWN_LAB, else "lab"
  std::string key;  // "" = the systemd credential when loaded, else none
};

// Adds --lab and --key to sub (in group, "" for none).
void add_lab_options(CLI::App* sub, LabOptions& o, const std::string& group = "Lab");
// The lab and key they name; a bad name or an unreadable key is bad usage (CLI::ValidationError).
LabSettings lab_settings_from(const LabOptions& o);
// The gate of a reader of the lab's messages (message_gate.hpp).
MessageGateOptions gate_options_from(const LabOptions& o, const std::string& lcm_url = "");

}  // namespace spindown::cli
