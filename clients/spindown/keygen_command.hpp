#pragma once
// `spindown keygen -o FILE`: a new lab key (32 random bytes from libsodium, mode 0600; an
// existing file is never overwritten). docs/security.md says where it goes and how each lab PC
// gets it.
#include <string>

namespace CLI {
class App;
}

namespace spindown::cli {

struct KeygenCommandOptions {
  std::string output;
};

void setup_keygen(CLI::App& app);
int run_keygen(const KeygenCommandOptions& options);

}  // namespace spindown::cli
