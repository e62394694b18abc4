#include "ecat/host/pcap_writer.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>

#include "base/real_time.hpp"

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
  ring_ = std::make_unique<uint8_t[]>(cap_);
  // Global header, written in our byte order (little-endian); readers detect the order from
  // the magic number. It goes out at once so a file is valid (if empty) from the start.
  uint8_t h[kFileHeaderSize]{};
  put_u32(h + 0, kMagicNanoseconds);
  put_u16(h + 4, 2);  // version 2.4
  put_u16(h + 6, 4);
  put_u32(h + 8, 0);   // thiszone
  put_u32(h + 12, 0);  // sigfigs
  put_u32(h + 16, kSnapLen);
  put_u32(h + 20, kLinkTypeEthernet);
  if (!write_all(fd_, h, sizeof(h))) {
    const int err = errno;
    ::close(fd_);
    throw std::runtime_error("cannot write pcap file " + path + ": " + std::strerror(err));
  }
}

PcapWriter::~PcapWriter() {
  close();
}

void PcapWriter::start() {
  if (thread_.joinable() || fd_ < 0) return;
  thread_ = std::thread([this] { run(); });
}

void PcapWriter::write(std::span<const uint8_t> frame) {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  write(frame,
        static_cast<uint64_t>(ts.tv_sec) * 1000000000ull + static_cast<uint64_t>(ts.tv_nsec));
}

void PcapWriter::write(std::span<const uint8_t> frame, uint64_t unix_time_ns) {
  if (fd_ < 0 || failed_.load(std::memory_order_relaxed)) return;
  const uint32_t incl = static_cast<uint32_t>(std::min<size_t>(frame.size(), kSnapLen));
  const size_t need = kRecordHeaderSize + incl;
  uint64_t head = head_.load(std::memory_order_relaxed);
  if (cap_ - (head - tail_.load(std::memory_order_acquire)) < need) {
    if (thread_.joinable() || need > cap_) {
      dropped_.fetch_add(1, std::memory_order_relaxed);  // never wait on the device thread
      return;
    }
    drain();  // no writer thread (tools, tests): write out here
  }
  uint8_t h[kRecordHeaderSize];
  put_u32(h + 0, static_cast<uint32_t>(unix_time_ns / 1000000000ull));
  put_u32(h + 4, static_cast<uint32_t>(unix_time_ns % 1000000000ull));
  put_u32(h + 8, incl);
  put_u32(h + 12, static_cast<uint32_t>(frame.size()));
  auto copy_in = [&](uint64_t at, const uint8_t* data, size_t len) {
    const size_t pos = static_cast<size_t>(at % cap_);
    const size_t first = std::min(len, cap_ - pos);
    std::memcpy(ring_.get() + pos, data, first);
    std::memcpy(ring_.get(), data + first, len - first);
  };
  copy_in(head, h, sizeof(h));
  copy_in(head + sizeof(h), frame.data(), incl);
  head_.store(head + need, std::memory_order_release);
  ++frames_;
}

void PcapWriter::drain() {
  const uint64_t head = head_.load(std::memory_order_acquire);
  const uint64_t tail = tail_.load(std::memory_order_relaxed);
  if (head == tail || fd_ < 0) return;
  const size_t pos = static_cast<size_t>(tail % cap_);
  const size_t len = static_cast<size_t>(head - tail);
  const size_t first = std::min(len, cap_ - pos);
  if (!failed_.load() &&
      (!write_all(fd_, ring_.get() + pos, first) || !write_all(fd_, ring_.get(), len - first))) {
    failed_.store(true);
  }
  tail_.store(head, std::memory_order_release);
}

void PcapWriter::run() {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  std::unique_lock lock(mutex_);
  for (;;) {
    cv_.wait_for(lock, kWritePeriod, [this] { return stop_ || flush_requested_; });
    drain();
    flush_requested_ = false;
    cv_.notify_all();
    if (stop_) return;
  }
}

bool PcapWriter::flush() {
  if (fd_ < 0) return false;
  std::unique_lock lock(mutex_);
  if (!thread_.joinable()) {
    drain();
  } else {
    const uint64_t target = head_.load(std::memory_order_acquire);
    flush_requested_ = true;
    cv_.notify_all();
    cv_.wait(lock, [&] { return tail_.load(std::memory_order_acquire) >= target; });
  }
  return !failed_.load();
}

void PcapWriter::close() {
  if (fd_ < 0) return;
  if (thread_.joinable()) {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  drain();
  ::close(fd_);
  fd_ = -1;
}

}  // namespace rackcat::ecat
