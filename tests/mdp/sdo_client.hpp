// A minimal CoE SDO client for the tests, written from ETG.1000.4 §5.5 (mailbox header:
// length, address, channel/priority, type 3 = CoE with counter in bits 4..6) and ETG.1000.6
// §5.6.2 (CoE header: service 2 request / 3 response in bits 12..15; SDO command specifiers:
// download initiate 0x21 (+0x10 complete access; expedited 0x23/0x27/0x2B/0x2F), upload
// initiate 0x40 (0x50 complete access), upload segment 0x60 (+toggle 0x10), abort 0x80 with
// the code in bytes 4..7 of the SDO part). It talks to mdp::Device::coe_request,
// framed as the firmware frames it (tests/support/mailbox_framing.hpp).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "mdp/device.hpp"
#include "tests/support/mailbox_framing.hpp"

namespace rackcat::mdp::testing {

class SdoClient {
 public:
  explicit SdoClient(Device& device) : device_(device) {}

  // Returns 0 or the SDO abort code.
  uint32_t download(uint16_t index, uint8_t sub, std::span<const uint8_t> data, bool ca = false) {
    std::vector<uint8_t> sdo;
    if (data.size() <= 4 && !data.empty()) {
      const uint8_t n = static_cast<uint8_t>(4 - data.size());
      sdo = {static_cast<uint8_t>(0x23 | (n << 2) | (ca ? 0x10 : 0)),
             lo(index),
             hi(index),
             sub,
             0,
             0,
             0,
             0};
      std::memcpy(&sdo[4], data.data(), data.size());
    } else {
      const uint32_t size = static_cast<uint32_t>(data.size());
      sdo = {static_cast<uint8_t>(0x21 | (ca ? 0x10 : 0)),
             lo(index),
             hi(index),
             sub,
             static_cast<uint8_t>(size),
             static_cast<uint8_t>(size >> 8),
             static_cast<uint8_t>(size >> 16),
             static_cast<uint8_t>(size >> 24)};
      sdo.insert(sdo.end(), data.begin(), data.end());
    }
    const std::vector<uint8_t> reply = exchange(sdo);
    if (reply.size() < 4) return 0xFFFFFFFF;
    if (reply[0] == 0x80) return abort_code(reply);
    EXPECT_EQ(reply[0] & 0xEF, 0x60) << "download response (bit 4 echoes complete access)";
    return 0;
  }

  uint32_t upload(uint16_t index, uint8_t sub, std::vector<uint8_t>& out, bool ca = false) {
    out.clear();
    std::vector<uint8_t> reply =
        exchange({static_cast<uint8_t>(ca ? 0x50 : 0x40), lo(index), hi(index), sub, 0, 0, 0, 0});
    if (reply.size() < 8) return 0xFFFFFFFF;
    if (reply[0] == 0x80) return abort_code(reply);
    const uint8_t cmd = reply[0];
    if (cmd & 0x02) {  // expedited: size in bits 2..3 when bit 0 is set
      const size_t n = (cmd & 0x01) ? 4 - ((cmd >> 2) & 3) : 4;
      out.assign(reply.begin() + 4, reply.begin() + 4 + static_cast<long>(n));
      return 0;
    }
    const uint32_t size =
        reply[4] | (reply[5] << 8) | (reply[6] << 16) | (uint32_t(reply[7]) << 24);
    out.assign(reply.begin() + 8, reply.end());
    uint8_t toggle = 0;
    while (out.size() < size) {
      std::vector<uint8_t> seg = exchange({static_cast<uint8_t>(0x60 | toggle)});
      if (seg.empty()) return 0xFFFFFFFF;
      if (seg[0] == 0x80) return abort_code(seg);
      size_t len = seg.size() - 1;
      if (len == 7) len -= (seg[0] >> 1) & 7;
      out.insert(out.end(), seg.begin() + 1, seg.begin() + 1 + static_cast<long>(len));
      toggle ^= 0x10;
      if (seg[0] & 0x01) break;
    }
    out.resize(std::min<size_t>(out.size(), size));
    return 0;
  }

  uint32_t write_u(uint16_t index, uint8_t sub, uint64_t value, size_t bytes) {
    std::vector<uint8_t> d(bytes);
    for (size_t i = 0; i < bytes; ++i) d[i] = static_cast<uint8_t>(value >> (8 * i));
    return download(index, sub, d);
  }
  uint32_t write_text(uint16_t index, uint8_t sub, const std::string& text) {
    return download(
        index, sub,
        std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }
  uint64_t read_u(uint16_t index, uint8_t sub) {
    std::vector<uint8_t> d;
    EXPECT_EQ(upload(index, sub, d), 0u) << std::hex << index << ":" << int(sub);
    uint64_t v = 0;
    for (size_t i = 0; i < d.size() && i < 8; ++i) v |= uint64_t{d[i]} << (8 * i);
    return v;
  }
  std::string read_text(uint16_t index, uint8_t sub) {
    std::vector<uint8_t> d;
    EXPECT_EQ(upload(index, sub, d), 0u);
    std::string s(d.begin(), d.end());
    return s.substr(0, s.find('\0'));
  }

 private:
  static uint8_t lo(uint16_t v) { return static_cast<uint8_t>(v); }
  static uint8_t hi(uint16_t v) { return static_cast<uint8_t>(v >> 8); }
  static uint32_t abort_code(const std::vector<uint8_t>& r) {
    return r[4] | (r[5] << 8) | (r[6] << 16) | (uint32_t(r[7]) << 24);
  }

  // Sends one CoE SDO request (the SDO part given), returns the SDO part of the reply.
  std::vector<uint8_t> exchange(const std::vector<uint8_t>& sdo) {
    counter_ = static_cast<uint8_t>(counter_ % 7 + 1);
    std::vector<uint8_t> body = sdo;
    while (body.size() < 8) body.push_back(0);  // an SDO request is at least 8 bytes
    const uint16_t len = static_cast<uint16_t>(2 + body.size());
    std::vector<uint8_t> req = {lo(len), hi(len), 0,
                                0,       0,       static_cast<uint8_t>(0x03 | (counter_ << 4)),
                                0x00,    0x20};  // CoE number 0, service 2 (SDO request)
    req.insert(req.end(), body.begin(), body.end());
    std::vector<uint8_t> reply(128);
    const size_t n = frame_.request(
        req, reply, [&](auto data, size_t, auto out) { return device_.coe_request(data, out); });
    if (n < 8) return {};
    const size_t mbx_len = reply[0] | (reply[1] << 8);
    EXPECT_EQ(reply[5] & 0x0F, 0x03) << "CoE reply";
    // An abort travels as an SDO request (service 2) with command 0x80, a response as service 3.
    EXPECT_EQ(reply[7] >> 4, reply[8] == 0x80 ? 0x02 : 0x03) << "SDO service";
    return std::vector<uint8_t>(reply.begin() + 8, reply.begin() + 6 + static_cast<long>(mbx_len));
  }

  Device& device_;
  uint8_t counter_ = 0;
  rackcat::testing::SlaveMailbox frame_;  // the firmware's side of the frame
};

// The fixture of the SDO tests: a default rack's device, brought to PREOP (ETG.1000.6 §5.6.1:
// SDO services from PREOP on), with an SdoClient on its mailbox. `make` builds another rack;
// `go` drives a transition the way the ESM does (request, then the state-change hook).
class DeviceSdoTest : public ::testing::Test {
 protected:
  // `state_dir_name`: this test's own state directory below the gtest temporary directory.
  explicit DeviceSdoTest(std::string state_dir_name) : state_dir_name_(std::move(state_dir_name)) {}

  void SetUp() override { make(default_rack()); }
  void make(RackConfig cfg) {
    DeviceOptions opt;
    opt.load_stored_parameters = false;
    opt.state_dir = ::testing::TempDir() + "/" + state_dir_name_;
    device = std::make_unique<Device>(std::move(cfg), opt);
    sdo = std::make_unique<SdoClient>(*device);
    go(EsmState::PreOp);
  }
  void go(EsmState to) {
    const EsmState from = device->state();
    ASSERT_EQ(device->request_state(from, to), 0);
    device->state_changed(from, to);
  }

  std::unique_ptr<Device> device;
  std::unique_ptr<SdoClient> sdo;

 private:
  std::string state_dir_name_;
};

// A default-rack device in PREOP whose state directory survives restart(): stored parameters
// are loaded as at power-on. `prefix` names the directory (plus the running test's name).
class RestartingDeviceTest : public ::testing::Test {
 protected:
  explicit RestartingDeviceTest(std::string prefix) : prefix_(std::move(prefix)) {}
  void SetUp() override {
    dir = ::testing::TempDir() + "/" + prefix_ +
          ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::remove_all(dir);
    restart();
  }
  void restart() {
    sdo.reset();
    device.reset();
    DeviceOptions opt;
    opt.state_dir = dir;
    device = std::make_unique<Device>(default_rack(), opt);
    sdo = std::make_unique<SdoClient>(*device);
    device->state_changed(EsmState::Init, EsmState::PreOp);
  }

  std::string dir;
  std::unique_ptr<Device> device;
  std::unique_ptr<SdoClient> sdo;

 private:
  std::string prefix_;
};

}  // namespace rackcat::mdp::testing
