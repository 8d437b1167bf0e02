#include "spindown/session_id.hpp"

#include <cerrno>
#include <cstring>
#include <fmt/format.h>
#include <stdexcept>
#include <sys/random.h>

#include "spindown/utf8_text.hpp"

namespace spindown {

std::uint64_t new_session_id() {
  for (int attempt = 0; attempt < 100; ++attempt) {
    std::uint64_t id = 0;
    const ssize_t got = ::getrandom(&id, sizeof id, 0);
    if (got == static_cast<ssize_t>(sizeof id)) {
      if (id != 0) return id;
      continue;
    }
    if (got < 0 && errno != EINTR)
      throw std::runtime_error(fmt::format("getrandom failed: {}", std::strerror(errno)));
  }
  throw std::runtime_error("getrandom gave no usable session id");
}

std::string session_text(std::uint64_t session) { return fmt::format("{:016x}", session); }

std::string shown_name(std::string_view name) {
  std::string out = text::escape_invalid_utf8(name.substr(0, 64));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  return out;
}

std::string source_text(std::string_view host, std::uint64_t session) {
  if (session == 0 && host.empty()) return "an unnamed source (a sender from before sources were named)";
  return fmt::format("host {} (session {})", host.empty() ? std::string("?") : shown_name(host), session_text(session));
}

}  // namespace spindown
