#include "spindown/host_name.hpp"

#include <unistd.h>

namespace spindown {

std::string host_name() {
  char buf[256] = {};
  if (::gethostname(buf, sizeof buf - 1) != 0 || buf[0] == '\0') return "unknown";
  return buf;
}

}  // namespace spindown
