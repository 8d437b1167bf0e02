#include "spindown/file_bytes.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

namespace spindown {

int open_for_reading(const std::string& path) { return ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK); }

void reads_blocking(int fd, const struct stat& st) {
  if (S_ISREG(st.st_mode)) return;
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
}

FdCloser::~FdCloser() { ::close(fd); }

std::optional<FileBytes> read_fd_bytes(int fd, const struct stat& st, const std::string& path, std::string* why,
                                       std::size_t max_bytes) {
  auto fail = [&](std::string msg) -> std::optional<FileBytes> {
    if (why) *why = std::move(msg);
    return std::nullopt;
  };
  if (S_ISDIR(st.st_mode)) return fail(fmt::format("cannot read {}: it is a directory", path));
  if (S_ISREG(st.st_mode) && static_cast<std::size_t>(st.st_size) > max_bytes)
    return fail(fmt::format("cannot read {}: {} bytes is more than the {} bytes a text recording may have", path,
                            st.st_size, max_bytes));
  // One byte more than the size, so the read that sees the end needs no growth.
  std::size_t capacity = S_ISREG(st.st_mode) ? static_cast<std::size_t>(st.st_size) + 1 : 0;
  FileBytes bytes{std::make_unique_for_overwrite<char[]>(capacity), 0};
  for (;;) {
    if (bytes.size == capacity) {
      if (capacity >= max_bytes) return fail(fmt::format("cannot read {}: more than {} bytes", path, max_bytes));
      capacity = std::min(max_bytes, std::max<std::size_t>(capacity * 2, 64 * 1024));
      auto larger = std::make_unique_for_overwrite<char[]>(capacity);
      if (bytes.size > 0) std::memcpy(larger.get(), bytes.data.get(), bytes.size);
      bytes.data = std::move(larger);
    }
    const ssize_t n = ::read(fd, bytes.data.get() + bytes.size, capacity - bytes.size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail(fmt::format("cannot read {}: {}", path, std::strerror(errno)));
    }
    if (n == 0) break;
    bytes.size += static_cast<std::size_t>(n);
    // A regular file read to the size fstat gave, with room left in the buffer: that is its end,
    // and the read that would return 0 is saved. A file that grew meanwhile filled the buffer.
    if (S_ISREG(st.st_mode) && bytes.size < capacity && bytes.size == static_cast<std::size_t>(st.st_size)) break;
  }
  return bytes;
}

std::optional<std::string> read_file_bytes(const std::string& path, std::string* why, std::size_t max_bytes) {
  const int fd = open_for_reading(path);
  if (fd < 0) {
    if (why) *why = fmt::format("cannot open {}: {}", path, std::strerror(errno));
    return std::nullopt;
  }
  FdCloser closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    if (why) *why = fmt::format("cannot read {}: {}", path, std::strerror(errno));
    return std::nullopt;
  }
  reads_blocking(fd, st);
  auto bytes = read_fd_bytes(fd, st, path, why, max_bytes);
  if (!bytes) return std::nullopt;
  return std::string(bytes->view());
}

}  // namespace spindown
