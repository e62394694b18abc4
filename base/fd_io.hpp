// Whole-buffer reads and writes on a file descriptor. POSIX read(2) and write(2) may move fewer
// bytes than asked and fail with EINTR when a signal arrives (POSIX.1-2017 read(), write()):
// this is the one loop every file reader and writer of rackcat uses for that.
#pragma once

#include <sys/types.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>

namespace rackcat::base {

// Reads until `size` bytes are in `data` or the file ends. Returns the bytes read (fewer than
// `size` only at the end of the file), or -1 with errno set when a read fails.
inline ssize_t read_fully(int fd, void* data, size_t size) {
  auto* p = static_cast<uint8_t*>(data);
  size_t got = 0;
  while (got < size) {
    const ssize_t n = ::read(fd, p + got, size - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return -1;
    if (n == 0) break;
    got += static_cast<size_t>(n);
  }
  return static_cast<ssize_t>(got);
}

// Writes all `size` bytes of `data`. Returns false with errno set when a write fails (a write
// that moves nothing without an error counts as EIO).
inline bool write_all(int fd, const void* data, size_t size) {
  const auto* p = static_cast<const uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    if (n == 0) {
      errno = EIO;
      return false;
    }
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

}  // namespace rackcat::base
