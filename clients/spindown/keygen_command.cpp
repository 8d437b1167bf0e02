#include "keygen_command.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <memory>

#include "exit_codes.hpp"
#include "spindown/lab_key.hpp"

namespace spindown::cli {

void setup_keygen(CLI::App& app) {
  auto opt = std::make_shared<KeygenCommandOptions>();
  CLI::App* sub = app.add_subcommand("keygen", "Make a new lab key: the file that signs and checks the lab's messages");
  sub->footer(
      "Writes 32 random bytes (libsodium) to a new file, mode 0600; an existing file is never overwritten. The same "
      "key goes to every lab PC, e.g. /etc/spindown/lab.key (root-only; the units load it with "
      "LoadCredential=lab-key:/etc/spindown/lab.key, which deploy/install-lab sets up when the file is there). The "
      "same as: head -c 32 /dev/urandom > FILE. See docs/security.md.\n"
      "Exit codes: 0 written, 1 the file could not be made, 2 bad usage.");
  sub->add_option("-o,--output", opt->output, "The key file to create")->required();
  sub->callback([opt]() {
    const int code = run_keygen(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_keygen(const KeygenCommandOptions& o) {
  std::string why;
  if (!write_new_lab_key(o.output, &why)) {
    fmt::print(stderr, "spindown keygen: {}\n", why);
    return exit_unusable;
  }
  const auto key = load_lab_key(o.output, &why);
  if (!key) {
    fmt::print(stderr, "spindown keygen: {}\n", why);
    return exit_unusable;
  }
  fmt::print("{}: a new lab key, id {} (copy this file to every lab PC, mode 0600)\n", o.output, key_id_text(key->id));
  return exit_ok;
}

}  // namespace spindown::cli
