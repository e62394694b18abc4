// A minimal SDO Information client for the tests, written from ETG.1000.6 §5.6.3: CoE service 8,
// an information header of opcode (bits 0..6, bit 7 "incomplete"), a reserved byte and 16 bits
// of fragments left; opcodes 1/2 OD list, 3/4 object description, 5/6 entry description,
// 7 error (abort code in the four bytes after the header). Fragments are collected until the
// "incomplete" bit is clear, polling the device for the rest as a master reads SM1 again.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "mdp/device.hpp"
#include "tests/support/mailbox_framing.hpp"

namespace rackcat::mdp::testing {

class SdoInfoClient {
 public:
  explicit SdoInfoClient(Device& device) : device_(device) {}

  // The data of the (reassembled) response, without the information header. `abort` gets the
  // abort code of an error response (0 otherwise).
  std::vector<uint8_t> request(uint8_t opcode, const std::vector<uint8_t>& data, uint32_t& abort) {
    abort = 0;
    std::vector<uint8_t> body = {opcode, 0, 0, 0};
    body.insert(body.end(), data.begin(), data.end());
    const uint16_t len = static_cast<uint16_t>(2 + body.size());
    counter_ = static_cast<uint8_t>(counter_ % 7 + 1);
    std::vector<uint8_t> req = {static_cast<uint8_t>(len),
                                static_cast<uint8_t>(len >> 8),
                                0,
                                0,
                                0,
                                static_cast<uint8_t>(0x03 | (counter_ << 4)),
                                0x00,
                                0x80};  // CoE number 0, service 8 (SDO Information)
    req.insert(req.end(), body.begin(), body.end());
    std::vector<uint8_t> out;
    std::vector<uint8_t> reply(1024);
    size_t n = frame_.request(
        req, reply, [&](auto data, size_t, auto out) { return device_.coe_request(data, out); });
    for (int guard = 0; guard < 1000 && n >= 12; ++guard) {
      const size_t mbx_len = reply[0] | (reply[1] << 8);
      EXPECT_EQ(reply[7] >> 4, 0x08) << "SDO Information service";
      const uint8_t op = reply[8];
      if ((op & 0x7F) == 0x07) {
        abort = reply[12] | (reply[13] << 8) | (reply[14] << 16) | (uint32_t(reply[15]) << 24);
        return {};
      }
      out.insert(out.end(), reply.begin() + 12, reply.begin() + 6 + static_cast<long>(mbx_len));
      if (!(op & 0x80)) break;
      n = frame_.poll(reply, [&](auto out) { return device_.coe_poll(out); });
    }
    return out;
  }

  // §5.6.3.5.2: index, data type, max subindex, object code, name.
  struct ObjectDescription {
    uint16_t data_type = 0;
    uint8_t max_subindex = 0;
    uint8_t object_code = 0;
    std::string name;
  };
  ObjectDescription object(uint16_t index, uint32_t& abort) {
    const auto d =
        request(0x03, {static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8)}, abort);
    ObjectDescription o;
    if (d.size() < 6) return o;
    o.data_type = static_cast<uint16_t>(d[2] | (d[3] << 8));
    o.max_subindex = d[4];
    o.object_code = d[5];
    o.name.assign(d.begin() + 6, d.end());
    return o;
  }

  // §5.6.3.6.2 with value info 0: index, subindex, value info, data type, bit length, access,
  // name.
  struct EntryDescription {
    uint16_t data_type = 0;
    uint16_t bit_length = 0;
    uint16_t access = 0;
    std::string name;
  };
  EntryDescription entry(uint16_t index, uint8_t sub, uint32_t& abort) {
    const auto d = request(
        0x05, {static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), sub, 0}, abort);
    EntryDescription e;
    if (d.size() < 10) return e;
    e.data_type = static_cast<uint16_t>(d[4] | (d[5] << 8));
    e.bit_length = static_cast<uint16_t>(d[6] | (d[7] << 8));
    e.access = static_cast<uint16_t>(d[8] | (d[9] << 8));
    e.name.assign(d.begin() + 10, d.end());
    return e;
  }

  // §5.6.3.3: the indices of list type 1 (all objects).
  std::vector<uint16_t> all_objects(uint32_t& abort) {
    const auto d = request(0x01, {0x01, 0x00}, abort);
    std::vector<uint16_t> out;
    for (size_t i = 2; i + 1 < d.size(); i += 2)
      out.push_back(static_cast<uint16_t>(d[i] | (d[i + 1] << 8)));
    return out;
  }

 private:
  Device& device_;
  uint8_t counter_ = 0;
  rackcat::testing::SlaveMailbox frame_;  // the firmware's side of the frame
};

}  // namespace rackcat::mdp::testing
