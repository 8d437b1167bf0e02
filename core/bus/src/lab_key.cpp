#include "spindown/lab_key.hpp"

#include <algorithm>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include "spindown/fail_why.hpp"
#include "spindown/trim.hpp"

namespace spindown {

namespace {

bool sodium_ready() {
  static const bool ok = ::sodium_init() >= 0;
  return ok;
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

LabKey lab_key_from_bytes(const std::array<unsigned char, lab_key_bytes>& bytes) {
  sodium_ready();
  LabKey k;
  k.bytes = bytes;
  static constexpr char label[] = "spindown lab key id";
  unsigned char digest[crypto_generichash_BYTES];
  crypto_generichash_state st;
  crypto_generichash_init(&st, nullptr, 0, sizeof digest);
  crypto_generichash_update(&st, reinterpret_cast<const unsigned char*>(label), sizeof label - 1);
  crypto_generichash_update(&st, bytes.data(), bytes.size());
  crypto_generichash_final(&st, digest, sizeof digest);
  std::uint32_t id = (std::uint32_t(digest[0]) << 24) | (std::uint32_t(digest[1]) << 16) |
                     (std::uint32_t(digest[2]) << 8) | std::uint32_t(digest[3]);
  if (id == 0) id = 1;
  k.id = static_cast<std::int32_t>(id);
  ::sodium_memzero(digest, sizeof digest);
  return k;
}

std::optional<LabKey> load_lab_key(const std::string& path, std::string* why) {
  if (!sodium_ready()) {
    fail_why(why, "libsodium could not be initialized");
    return std::nullopt;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) {
    fail_why(why, fmt::format("lab key {}: {}", path, std::strerror(errno)));
    return std::nullopt;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    fail_why(why, fmt::format("lab key {}: not a regular file", path));
    return std::nullopt;
  }
  char buf[160];
  std::size_t got = 0;
  for (;;) {
    const ssize_t n = ::read(fd, buf + got, sizeof buf - got);
    if (n > 0 && (got += static_cast<std::size_t>(n)) < sizeof buf) continue;
    if (n < 0 && errno == EINTR) continue;
    break;
  }
  ::close(fd);
  std::array<unsigned char, lab_key_bytes> bytes{};
  const std::string_view text = trim(std::string_view(buf, got));
  bool ok = false;
  if (got == lab_key_bytes) {
    std::memcpy(bytes.data(), buf, lab_key_bytes);
    ok = true;
  } else if (text.size() == 2 * lab_key_bytes) {
    ok = true;
    for (std::size_t i = 0; i < lab_key_bytes && ok; ++i) {
      const int hi = hex_value(text[2 * i]), lo = hex_value(text[2 * i + 1]);
      ok = hi >= 0 && lo >= 0;
      bytes[i] = static_cast<unsigned char>(hi * 16 + lo);
    }
  }
  ::sodium_memzero(buf, sizeof buf);
  if (!ok) {
    fail_why(why, fmt::format("lab key {}: {} bytes; a key is {} bytes (spindown keygen -o FILE, or head -c 32 "
                              "/dev/urandom > FILE) or {} hex digits",
                              path, got >= sizeof buf ? std::string("more than 160") : std::to_string(got), lab_key_bytes,
                              2 * lab_key_bytes));
    return std::nullopt;
  }
  LabKey k = lab_key_from_bytes(bytes);
  ::sodium_memzero(bytes.data(), bytes.size());
  k.path = path;
  if (st.st_mode & S_IROTH)
    k.warning = fmt::format("lab key {} is readable by every user (mode {:04o}): chmod 600 it (or 640 root:spindown)",
                            path, st.st_mode & 07777);
  return k;
}

LabKeyChoice choose_lab_key(const std::string& option_path, const std::optional<std::string>& credentials_dir) {
  LabKeyChoice c;
  std::vector<std::string> paths;
  if (!option_path.empty()) {
    for (std::size_t at = 0; at <= option_path.size();) {  // NEW.key,OLD.key: the first signs
      const std::size_t comma = std::min(option_path.find(',', at), option_path.size());
      if (comma > at) paths.push_back(option_path.substr(at, comma - at));
      at = comma + 1;
    }
    c.source = "--key " + option_path;
  } else if (credentials_dir && !credentials_dir->empty()) {
    const std::string candidate = *credentials_dir + "/" + lab_key_credential;
    struct stat st {};
    if (::stat(candidate.c_str(), &st) != 0) return c;  // no key loaded: signing off
    paths.push_back(candidate);
    c.source = fmt::format("systemd credential {}", lab_key_credential);
    const std::string previous = *credentials_dir + "/" + lab_key_previous_credential;
    if (::stat(previous.c_str(), &st) == 0) {
      paths.push_back(previous);
      c.source += fmt::format(" (and {})", lab_key_previous_credential);
    }
  }
  if (paths.empty()) return c;
  for (const std::string& path : paths) {
    std::string why;
    std::optional<LabKey> key = load_lab_key(path, &why);
    if (!key) {
      c.key.reset();
      c.also_accepted.clear();
      c.error = why;
      return c;
    }
    if (!c.key)
      c.key = std::move(key);
    else
      c.also_accepted.push_back(std::move(*key));
  }
  return c;
}

LabKeyChoice choose_lab_key(const std::string& option_path) {
  const char* dir = std::getenv("CREDENTIALS_DIRECTORY");
  return choose_lab_key(option_path, dir ? std::optional<std::string>(dir) : std::nullopt);
}

bool write_new_lab_key(const std::string& path, std::string* why) {
  if (!sodium_ready()) return fail_why(why, "libsodium could not be initialized");
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0)
    return fail_why(why, errno == EEXIST ? fmt::format("{} exists: a key is never overwritten (remove it first, and "
                                                       "give every lab PC the new one)",
                                                       path)
                                         : fmt::format("cannot create {}: {}", path, std::strerror(errno)));
  std::array<unsigned char, lab_key_bytes> bytes{};
  ::randombytes_buf(bytes.data(), bytes.size());
  std::size_t done = 0;
  bool ok = true;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ok = false;
      break;
    }
    done += static_cast<std::size_t>(n);
  }
  ::sodium_memzero(bytes.data(), bytes.size());
  const int err = errno;
  if (::fsync(fd) != 0) ok = false;
  ::close(fd);
  if (!ok) {
    ::unlink(path.c_str());
    return fail_why(why, fmt::format("cannot write {}: {}", path, std::strerror(err)));
  }
  return true;
}

std::string key_id_text(std::int32_t id) { return fmt::format("{:#010x}", static_cast<std::uint32_t>(id)); }

}  // namespace spindown
