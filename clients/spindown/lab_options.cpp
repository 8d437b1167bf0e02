#include "lab_options.hpp"

#include <CLI/CLI.hpp>

#include "input_options.hpp"

namespace spindown::cli {

void add_lab_options(CLI::App* sub, LabOptions& o, const std::string& group) {
  sub->add_option("--lab", o.lab, lab_option_help)->group(group);
  sub->add_option("--key", o.key,
                  "Lab key file (32 bytes; spindown keygen): use only messages signed with it, and name the unsigned, "
                  "wrongly signed and replayed ones (default: none, every message is used); NEW,OLD while keys change: "
                  "either key's messages are used")
      ->group(group);
}

LabSettings lab_settings_from(const LabOptions& o) {
  std::string why;
  auto s = resolve_lab_settings(o.lab, o.key, &why);
  if (!s) bad_usage(why);
  return *s;
}

MessageGateOptions gate_options_from(const LabOptions& o, const std::string& lcm_url) {
  return lab_gate(lab_settings_from(o), lcm_url);
}

}  // namespace spindown::cli
