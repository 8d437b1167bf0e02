#include "service_command_line.hpp"

#include <fmt/format.h>

namespace spindown::service {

void LabConnectionOptions::add_to(CLI::App& app, bool receives, const char* lab_help, const char* key_help) {
  app.add_option("--lcm-url", lcm_url_, "LCM URL (default: LCM_DEFAULT_URL or LCM's default)");
  app.add_option("--lab", lab_, lab_help);
  app.add_option("--key", key_, key_help);
  if (receives)
    app.add_option("--recv-buf", recv_buf_, "udpm receive buffer bytes added to the URL (0 = leave the URL alone)");
  else
    recv_buf_ = 0;  // a program that only sends keeps the URL as given
}

std::optional<LabConnection> LabConnectionOptions::resolve(std::string* why) const {
  auto lab = resolve_lab_settings(lab_, key_, why);
  if (!lab) return std::nullopt;
  return LabConnection{with_receive_buffer(lcm_url_, recv_buf_), std::move(*lab)};
}

std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help is 0; any bad usage is 2 (design §5)
  }
  return std::nullopt;
}

int bad_usage(std::string_view program, std::string_view why) {
  fmt::print(stderr, "{}: {}\n", program, why);
  return 2;
}

}  // namespace spindown::service
