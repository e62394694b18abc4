// A default-rack mdp::Device with a modules::Rack on a manual clock, driven cycle by cycle the
// way the ESC drives it: outputs unpacked (on_outputs), then inputs packed (before_inputs).
#pragma once

#include <gtest/gtest.h>

#include <bit>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"
#include "modules/rack/rack.hpp"

namespace rackcat::modules::testing {

inline mdp::DeviceOptions device_options() {
  mdp::DeviceOptions o;
  o.state_dir = ::testing::TempDir() + "rackcat-modules-state";
  o.load_stored_parameters = false;
  return o;
}

inline RackOptions rack_options(double* clock) {
  RackOptions o;
  o.clock = [clock] { return *clock; };
  return o;
}

struct Emergency {
  uint16_t code;
  uint8_t reg;
  std::array<uint8_t, 5> data;
};

class RackTest : public ::testing::Test {
 protected:
  RackTest() : RackTest(mdp::default_rack()) {}
  explicit RackTest(mdp::RackConfig config)
      : device(std::move(config), device_options()), rack(device, rack_options(&clock)) {
    drain_emergencies();
  }

  void go(EsmState from, EsmState to) { device.state_changed(from, to); }
  void to_op() {
    go(EsmState::Init, EsmState::PreOp);
    go(EsmState::PreOp, EsmState::SafeOp);
    go(EsmState::SafeOp, EsmState::Op);
  }
  // One process-data cycle of 1 ms.
  void cycle() {
    clock += 0.001;
    device.write_outputs({});
    in.assign(device.input_bytes(), 0);
    device.read_inputs(in);
  }

  CardDriver& at(uint8_t rim, uint8_t slot) {
    CardDriver* d = rack.driver_at(rim, slot);
    EXPECT_NE(d, nullptr) << "rim " << int(rim) << " slot " << int(slot);
    return *d;
  }
  coe::Object& obj(uint16_t index) {
    coe::Object* o = device.dictionary().find(index);
    EXPECT_NE(o, nullptr) << std::hex << index;
    return *o;
  }
  coe::Object& module_obj(CardDriver& d, uint16_t base, uint8_t nibble) {
    return obj(d.module().index(base, nibble));
  }
  float real(uint16_t index, uint8_t sub) {
    return std::bit_cast<float>(static_cast<uint32_t>(obj(index).get_u(sub)));
  }

  // CoE Emergency messages (ETG.1000.6 §5.6.4) as the device's CoE poll gives their mailbox
  // data: 2-byte CoE header (service 1 = emergency), error code (LE16), error register, 5
  // data bytes.
  std::vector<Emergency> drain_emergencies() {
    std::vector<Emergency> out;
    uint8_t buf[256];
    for (size_t n; (n = device.coe_poll(buf)) > 0;) {
      if (n < 10 || (buf[1] >> 4) != 0x01) continue;
      Emergency e{static_cast<uint16_t>(buf[2] | buf[3] << 8), buf[4], {}};
      std::copy(buf + 5, buf + 10, e.data.begin());
      out.push_back(e);
    }
    return out;
  }
  static bool has_code(const std::vector<Emergency>& v, uint16_t code) {
    for (const auto& e : v)
      if (e.code == code) return true;
    return false;
  }

  double clock = 0.0;
  mdp::Device device;
  Rack rack;
  std::vector<uint8_t> in;
};

}  // namespace rackcat::modules::testing
