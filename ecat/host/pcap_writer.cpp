#include "ecat/host/pcap_writer.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>

namespace rackcat::ecat {
namespace {

void put_u16(uint8_t* p, uint16_t v) {
  p[0] = static_cast<uint8_t>(v);
  p[1] = static_cast<uint8_t>(v >> 8);
}

void put_u32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}

bool write_all(int fd, const uint8_t* data, size_t len) {
  while (len > 0) {
    ssize_t n = ::write(fd, data, len);
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    data += n;
    len -= static_cast<size_t>(n);
  }
  return true;
}

}  // namespace

PcapWriter::PcapWriter(const std::string& path, size_t buffer_size)
    : path_(path), cap_(std::max<size_t>(buffer_size, 4096)) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw std::runtime_error("cannot create pcap file " + path + ": " + std::strerror(errno));
  }
  buf_ = std::make_unique<uint8_t[]>(cap_);
  // Global header, written in our byte order (little-endian); readers detect the order from
  // the magic number.
  uint8_t h[kFileHeaderSize]{};
  put_u32(h + 0, kMagicNanoseconds);
  put_u16(h + 4, 2);  // version 2.4
  put_u16(h + 6, 4);
  put_u32(h + 8, 0);   // thiszone
  put_u32(h + 12, 0);  // sigfigs
  put_u32(h + 16, kSnapLen);
  put_u32(h + 20, kLinkTypeEthernet);
  append(h, sizeof(h));
  // The header goes out at once so a file is valid (if empty) from the start.
  if (!flush()) {
    ::close(fd_);
    throw std::runtime_error("cannot write pcap file " + path + ": " + std::strerror(errno));
  }
}

PcapWriter::~PcapWriter() {
  close();
}

void PcapWriter::write(std::span<const uint8_t> frame) {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  write(frame,
        static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec));
}

void PcapWriter::write(std::span<const uint8_t> frame, uint64_t unix_time_ns) {
  if (fd_ < 0 || failed_) return;
  const uint32_t incl = static_cast<uint32_t>(std::min<size_t>(frame.size(), kSnapLen));
  uint8_t h[kRecordHeaderSize];
  put_u32(h + 0, static_cast<uint32_t>(unix_time_ns / 1000000000ull));
  put_u32(h + 4, static_cast<uint32_t>(unix_time_ns % 1000000000ull));
  put_u32(h + 8, incl);
  put_u32(h + 12, static_cast<uint32_t>(frame.size()));
  append(h, sizeof(h));
  append(frame.data(), incl);
  ++frames_;
}

void PcapWriter::append(const uint8_t* data, size_t len) {
  if (used_ + len > cap_) {
    if (!flush()) return;
    if (len > cap_) {
      // Larger than the whole buffer (tiny buffer and a jumbo frame): straight through.
      if (!write_all(fd_, data, len)) failed_ = true;
      return;
    }
  }
  std::memcpy(buf_.get() + used_, data, len);
  used_ += len;
}

bool PcapWriter::flush() {
  if (fd_ < 0) return false;
  if (failed_) return false;
  if (used_ > 0 && !write_all(fd_, buf_.get(), used_)) failed_ = true;
  used_ = 0;
  return !failed_;
}

void PcapWriter::close() {
  if (fd_ < 0) return;
  flush();
  ::close(fd_);
  fd_ = -1;
}

}  // namespace rackcat::ecat
