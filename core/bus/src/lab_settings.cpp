#include "spindown/lab_settings.hpp"

#include <fmt/format.h>
#include <stdexcept>

#include "spindown/lab_name.hpp"

namespace spindown {

std::optional<LabSettings> resolve_lab_settings(const std::string& lab_option, const std::string& key_option,
                                                std::string* why) {
  LabSettings s;
  try {
    s.lab = choose_lab_name(lab_option);
  } catch (const std::invalid_argument& e) {
    if (why) *why = e.what();
    return std::nullopt;
  }
  LabKeyChoice k = choose_lab_key(key_option);
  if (!k.error.empty()) {
    if (why) *why = k.error;
    return std::nullopt;
  }
  s.key = std::move(k.key);
  s.also_accepted = std::move(k.also_accepted);
  s.key_source = std::move(k.source);
  return s;
}

std::string lab_settings_text(const LabSettings& s) {
  if (!s.key) return fmt::format("lab '{}'; messages not signed (no lab key)", s.lab);
  std::string also;
  for (const LabKey& k : s.also_accepted) also += fmt::format(", {}", key_id_text(k.id));
  return fmt::format("lab '{}'; messages signed with key {} ({}){}", s.lab, key_id_text(s.key->id), s.key_source,
                     also.empty() ? std::string() : fmt::format("; also accepted while keys change: key{}", also.substr(1)));
}

}  // namespace spindown
