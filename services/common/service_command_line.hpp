#pragma once
// One way to assemble a service (issue 42): every service that listens to or sends on the lab's
// LCM takes --lcm-url, --lab, --key and --recv-buf the same way and turns them into one
// LabConnection (the URL with its receive buffer, the lab's name and key, and the message gate
// built from both, lab_gate()); its command line ends the program with the design's exit codes
// (--help 0, bad usage 2, with "program: why" on stderr).
#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "spindown/lab_settings.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/message_gate.hpp"

namespace spindown::service {

struct LabConnection {
  std::string lcm_url;  // --lcm-url with the receive buffer --recv-buf asks for
  LabSettings lab;      // --lab, --key
  MessageGateOptions gate() const { return lab_gate(lab, lcm_url); }
};

class LabConnectionOptions {
 public:
  // --lcm-url, --lab, --key, and --recv-buf unless the program only sends; lab_help and key_help
  // where a program's words differ (the logger records every lab's messages and refuses none).
  void add_to(CLI::App& app, bool receives = true, const char* lab_help = lab_option_help,
              const char* key_help = key_option_help);
  // nullopt and *why when --lab or --key cannot be used.
  std::optional<LabConnection> resolve(std::string* why) const;

 private:
  std::string lcm_url_, lab_, key_;
  long recv_buf_ = services_recv_buf_bytes;
};

// app.parse(argc, argv): nullopt to go on, else the exit code (--help 0, bad usage 2).
std::optional<int> parse(CLI::App& app, int argc, char** argv);
// "program: why" on stderr; 2, bad usage.
int bad_usage(std::string_view program, std::string_view why);

}  // namespace spindown::service
