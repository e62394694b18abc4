// `--pcap FILE`: every EtherCAT frame in and out, in the classic libpcap file format
// (LINKTYPE_ETHERNET, nanosecond timestamps) that Wireshark and tshark open directly.
//
// The device thread only copies each record into a fixed ring (no system call, no
// allocation, never a wait). Once start() has been called, a writer thread of its own empties
// the ring into the file every kWritePeriod, so a process killed with SIGKILL loses at most
// that much (plus what the kernel had not yet taken); a ring the writer cannot keep up with
// drops the frame and counts it (dropped()) instead of stalling the cycle. Before start()
// (tools, tests) a full ring is written out on the calling thread.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>

namespace rackcat::ecat {

class PcapWriter {
 public:
  // libpcap file format: magic 0xA1B23C4D marks nanosecond timestamps; link type 1 is
  // Ethernet (tcpdump.org LINKTYPE_ETHERNET). Frames longer than kSnapLen are cut there.
  static constexpr uint32_t kMagicNanoseconds = 0xA1B23C4D;
  static constexpr uint32_t kLinkTypeEthernet = 1;
  static constexpr uint32_t kSnapLen = 65535;
  static constexpr size_t kFileHeaderSize = 24;
  static constexpr size_t kRecordHeaderSize = 16;
  static constexpr std::chrono::milliseconds kWritePeriod{20};

  // Creates (truncates) the file and writes the file header; throws std::runtime_error with
  // the file name and reason when it cannot. `buffer_size` is the ring's size in bytes.
  explicit PcapWriter(const std::string& path, size_t buffer_size = 4 << 20);
  ~PcapWriter();  // writes what is left and closes
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;

  // Starts the writer thread (after privileges are dropped: threads must not predate it).
  void start();

  // Appends one frame stamped with the current wall-clock time (CLOCK_REALTIME, which is
  // what capture tools show).
  void write(std::span<const uint8_t> frame);
  // Appends one frame with an explicit timestamp in nanoseconds since the Unix epoch.
  void write(std::span<const uint8_t> frame, uint64_t unix_time_ns);

  // Writes everything recorded so far to the file (waits for the writer thread). Returns false
  // after a write error (sticky: later records are dropped rather than leaving a corrupt file).
  bool flush();
  void close();

  const std::string& path() const { return path_; }
  uint64_t frames_written() const { return frames_; }  // recorded (accepted into the ring)
  uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }
  bool ok() const { return !failed_.load(); }

 private:
  void drain();  // ring -> file, on the writer thread (or the caller before start())
  void run();

  std::string path_;
  int fd_ = -1;
  std::unique_ptr<uint8_t[]> ring_;
  size_t cap_ = 0;
  std::atomic<uint64_t> head_{0};  // bytes produced (device thread)
  std::atomic<uint64_t> tail_{0};  // bytes written (writer)
  uint64_t frames_ = 0;
  std::atomic<uint64_t> dropped_{0};
  std::atomic<bool> failed_{false};
  std::mutex mutex_;  // writer thread state and drain() exclusion
  std::condition_variable cv_;
  bool stop_ = false;
  bool flush_requested_ = false;
  std::thread thread_;
};

}  // namespace rackcat::ecat
