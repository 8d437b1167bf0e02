#pragma once
// Reading a recording's bytes: a file, a pipe or a FIFO (without hanging on one that has no
// writer), refusing what is too large before it exhausts memory. Shared by the text readers and
// read_recordings.
#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <sys/stat.h>

namespace spindown {

// Opens path for reading without blocking on a FIFO that has no writer yet (which would hang
// forever). Call reads_blocking once fstat has said what it is.
int open_for_reading(const std::string& path);

// Makes reads of anything but a regular file blocking again, so a pipe with a slow writer is
// read to its end (a FIFO without a writer then reads as empty). A regular file's reads never
// block: its two fcntl calls are saved (a quarter of a small file's system calls).
void reads_blocking(int fd, const struct stat& st);

struct FdCloser {
  int fd;
  ~FdCloser();
};

// A file's bytes, in a buffer that is not zero-filled before the read overwrites it.
struct FileBytes {
  std::unique_ptr<char[]> data;
  std::size_t size = 0;
  std::string_view view() const { return {data.get(), size}; }
};

// The bytes of an open fd (st: its fstat), at most max_bytes; nullopt and *why naming path.
std::optional<FileBytes> read_fd_bytes(int fd, const struct stat& st, const std::string& path, std::string* why,
                                       std::size_t max_bytes);

// The whole file in one read. nullopt and *why ("cannot open FILE: No such file or directory")
// when it cannot be read; files over max_bytes are refused rather than exhaust memory.
std::optional<std::string> read_file_bytes(const std::string& path, std::string* why,
                                           std::size_t max_bytes = std::size_t{1} << 30);

}  // namespace spindown
