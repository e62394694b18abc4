// PcapWriter: files in the classic libpcap format (tcpdump.org "pcap savefile format":
// 24-byte global header, 16-byte record headers), which Wireshark and tshark open.
#include <gtest/gtest.h>

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "ecat/host/pcap_writer.hpp"

namespace rackcat::ecat {
namespace {

std::string temp_path(const char* name) {
  return ::testing::TempDir() + "rackcat_" + std::to_string(getpid()) + "_" + name;
}

std::vector<uint8_t> read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

TEST(LinkPcap, GlobalHeaderIsNanosecondEthernet) {
  const auto path = temp_path("header.pcap");
  { PcapWriter w(path); }
  const auto bytes = read_file(path);
  // Magic 0xA1B23C4D (nanosecond resolution) little-endian, version 2.4, thiszone 0,
  // sigfigs 0, snaplen 65535, network 1 (LINKTYPE_ETHERNET).
  const std::vector<uint8_t> expected = {0x4D, 0x3C, 0xB2, 0xA1, 0x02, 0x00, 0x04, 0x00,
                                         0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
                                         0xFF, 0xFF, 0x00, 0x00, 0x01, 0x00, 0x00, 0x00};
  EXPECT_EQ(bytes, expected);
  std::remove(path.c_str());
}

TEST(LinkPcap, RecordCarriesTimestampLengthsAndBytes) {
  const auto path = temp_path("record.pcap");
  const std::vector<uint8_t> frame = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x02, 0x00,
                                      0x00, 0x00, 0x00, 0x01, 0x88, 0xA4, 0x0E, 0x10};
  {
    PcapWriter w(path);
    // 2026-01-02 03:04:05.000000123 UTC = 1767323045 s + 123 ns.
    w.write(frame, 1767323045ull * 1000000000ull + 123);
    EXPECT_EQ(w.frames_written(), 1u);
  }
  const auto bytes = read_file(path);
  ASSERT_EQ(bytes.size(), 24u + 16u + frame.size());
  const std::vector<uint8_t> record_header(bytes.begin() + 24, bytes.begin() + 40);
  // ts_sec 1767323045 = 0x695735A5, ts_nsec 123, incl_len 16, orig_len 16.
  const std::vector<uint8_t> expected = {0xA5, 0x35, 0x57, 0x69, 0x7B, 0x00, 0x00, 0x00,
                                         0x10, 0x00, 0x00, 0x00, 0x10, 0x00, 0x00, 0x00};
  EXPECT_EQ(record_header, expected);
  EXPECT_EQ(std::vector<uint8_t>(bytes.begin() + 40, bytes.end()), frame);
  std::remove(path.c_str());
}

TEST(LinkPcap, BufferedRecordsReachTheFileOnFlushAndInOrder) {
  const auto path = temp_path("buffered.pcap");
  PcapWriter w(path, 4096);
  std::vector<uint8_t> frame(60, 0);
  for (int i = 0; i < 200; ++i) {  // 200 x 76 bytes: several buffer refills
    frame[0] = static_cast<uint8_t>(i);
    w.write(frame, 1'000'000'000ull * 1700000000ull + static_cast<uint64_t>(i));
  }
  ASSERT_TRUE(w.flush());
  const auto bytes = read_file(path);
  ASSERT_EQ(bytes.size(), 24u + 200u * (16u + 60u));
  for (int i = 0; i < 200; ++i) {
    const size_t rec = 24 + static_cast<size_t>(i) * 76;
    EXPECT_EQ(bytes[rec + 4], static_cast<uint8_t>(i));   // ts_nsec low byte
    EXPECT_EQ(bytes[rec + 16], static_cast<uint8_t>(i));  // first frame byte
  }
  w.close();
  std::remove(path.c_str());
}

TEST(LinkPcap, UnwritablePathIsAnErrorNamingTheFile) {
  try {
    PcapWriter w("/nonexistent-dir/x.pcap");
    FAIL() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/x.pcap"), std::string::npos);
  }
}

}  // namespace
}  // namespace rackcat::ecat

namespace rackcat::ecat {
namespace {

// Issue 14 item 9: with its writer thread running, a full ring drops and counts frames; the
// device thread's write() never waits. The file is a FIFO nobody reads, so the writer blocks.
TEST(LinkPcap, AFullRingDropsAndCountsInsteadOfBlocking) {
  const auto path = temp_path("blocked.fifo");
  std::remove(path.c_str());
  ASSERT_EQ(::mkfifo(path.c_str(), 0600), 0);
  const int reader = ::open(path.c_str(), O_RDONLY | O_NONBLOCK);  // lets the writer open
  ASSERT_GE(reader, 0);
  {
    PcapWriter w(path, 64 * 1024);
    w.start();
    std::vector<uint8_t> frame(1000, 0xA5);
    // Nothing drains the FIFO until the loop is over, so a write() that waited for the writer
    // thread would never return (ctest's timeout); finishing with drops is the proof, no clock.
    for (int i = 0; i < 2000; ++i) {  // 2 MB: far more than the pipe and the ring hold
      w.write(frame, 1);
    }
    EXPECT_GT(w.dropped(), 0u);
    EXPECT_EQ(w.frames_written() + w.dropped(), 2000u);
    // Unblock the writer so it can finish: read everything until it closes.
    std::thread drain([reader] {
      char buf[65536];
      for (;;) {
        const ssize_t n = ::read(reader, buf, sizeof buf);
        if (n == 0) break;
        if (n < 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    });
    w.close();
    drain.join();
  }
  ::close(reader);
  std::remove(path.c_str());
}

// The writer thread writes on its own: records reach the file within a few write periods
// without any flush() (what survives a SIGKILL).
TEST(LinkPcap, TheWriterThreadWritesWithoutFlush) {
  const auto path = temp_path("periodic.pcap");
  PcapWriter w(path);
  w.start();
  std::vector<uint8_t> frame(60, 0x11);
  for (int i = 0; i < 10; ++i) w.write(frame, 1);
  std::this_thread::sleep_for(PcapWriter::kWritePeriod * 5);
  EXPECT_EQ(read_file(path).size(), 24u + 10u * 76u);
  w.close();
  std::remove(path.c_str());
}

// The scheduling policy (field 41 of /proc/self/task/TID/stat, proc(5)) of every thread of
// this process except the calling one.
std::vector<int> other_threads_policies() {
  std::vector<int> policies;
  const std::string self = std::to_string(gettid());
  DIR* d = opendir("/proc/self/task");
  if (d == nullptr) return policies;
  while (const dirent* e = readdir(d)) {
    const std::string tid = e->d_name;
    if (tid == "." || tid == ".." || tid == self) continue;
    std::ifstream f("/proc/self/task/" + tid + "/stat");
    std::string line;
    std::getline(f, line);
    // the command name (field 2) is in parentheses and may hold spaces: count after it
    const size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream rest(line.substr(close + 2));
    std::string field;
    for (int n = 3; n <= 41 && rest >> field; ++n) {
      if (n == 41) policies.push_back(std::stoi(field));
    }
  }
  closedir(d);
  return policies;
}

// rackcat runs under `chrt -f` and Linux threads inherit their creator's policy: the capture
// writer must not keep SCHED_FIFO, or its megabyte writes hold the CPU the device thread
// needs to answer the master within its timeout (base/real_time.hpp).
TEST(LinkPcap, TheWriterThreadLeavesTheRealTimeClass) {
  sched_param rt{};
  rt.sched_priority = 1;
  if (pthread_setschedparam(pthread_self(), SCHED_FIFO, &rt) != 0) {
    GTEST_SKIP() << "needs permission for SCHED_FIFO (root or CAP_SYS_NICE)";
  }
  const auto path = temp_path("policy.pcap");
  {
    PcapWriter w(path);
    w.start();
    std::vector<uint8_t> frame(60, 0x22);
    w.write(frame, 1);
    ASSERT_TRUE(w.flush());  // the writer thread has run its first pass
    const auto policies = other_threads_policies();
    ASSERT_FALSE(policies.empty());
    for (int p : policies) EXPECT_EQ(p, SCHED_OTHER);
  }
  sched_param normal{};
  EXPECT_EQ(pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal), 0);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace rackcat::ecat
