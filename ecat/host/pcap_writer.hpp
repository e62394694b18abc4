// `--pcap FILE`: every EtherCAT frame in and out, in the classic libpcap file format
// (LINKTYPE_ETHERNET, nanosecond timestamps) that Wireshark and tshark open directly.
//
// Records go to a fixed in-memory buffer written out when it fills and on flush()/close(),
// so recording a frame costs a copy and no system call on most frames, and never allocates.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

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

  // Creates (truncates) the file and writes the file header; throws std::runtime_error with
  // the file name and reason when it cannot.
  explicit PcapWriter(const std::string& path, size_t buffer_size = 1 << 20);
  ~PcapWriter();  // flushes and closes
  PcapWriter(const PcapWriter&) = delete;
  PcapWriter& operator=(const PcapWriter&) = delete;

  // Appends one frame stamped with the current wall-clock time (CLOCK_REALTIME, which is
  // what capture tools show).
  void write(std::span<const uint8_t> frame);
  // Appends one frame with an explicit timestamp in nanoseconds since the Unix epoch.
  void write(std::span<const uint8_t> frame, uint64_t unix_time_ns);

  // Writes the buffered records to the file. Returns false after a write error (the error
  // is sticky: later records are dropped rather than leaving a corrupt file).
  bool flush();
  void close();

  const std::string& path() const { return path_; }
  uint64_t frames_written() const { return frames_; }
  bool ok() const { return !failed_; }

 private:
  void append(const uint8_t* data, size_t len);

  std::string path_;
  int fd_ = -1;
  std::unique_ptr<uint8_t[]> buf_;
  size_t cap_ = 0;
  size_t used_ = 0;
  uint64_t frames_ = 0;
  bool failed_ = false;
};

}  // namespace rackcat::ecat
