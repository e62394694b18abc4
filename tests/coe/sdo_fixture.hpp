// A slave's SDO server on the test dictionary, with helpers that frame requests the way a
// master does (ETG.1000.4 §5.6 mailbox header, ETG.1000.6 §5.6.1 CoE header).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "coe/sdo_server.hpp"
#include "tests/coe/test_dictionary.hpp"

namespace rackcat::coe::test {

using Bytes = std::vector<uint8_t>;

// Mailbox header + CoE header + body, as a master writes it into SM0.
inline Bytes coe_message(uint8_t counter, uint8_t service, const Bytes& body) {
  const uint16_t len = static_cast<uint16_t>(2 + body.size());
  Bytes m(8 + body.size());
  m[0] = static_cast<uint8_t>(len);
  m[1] = static_cast<uint8_t>(len >> 8);
  m[5] = static_cast<uint8_t>(0x03 | (counter << 4));  // CoE, counter in bits 4-6
  m[7] = static_cast<uint8_t>(service << 4);           // CoE service in bits 12-15
  std::copy(body.begin(), body.end(), m.begin() + 8);
  return m;
}

class SdoTest : public ::testing::Test {
 protected:
  SdoTest() : od(make_test_dictionary()), server(od) {}

  // Sends one request (next master counter 1..7) and returns the reply mailbox.
  Bytes send(const Bytes& message, EsmState state = EsmState::PreOp, size_t mailbox = 128) {
    Bytes reply(mailbox, 0xEE);
    const size_t n = server.handle(message, reply, state);
    reply.resize(n);
    return reply;
  }
  Bytes sdo(const Bytes& body, EsmState state = EsmState::PreOp, size_t mailbox = 128) {
    return send(coe_message(next_counter(), 2, body), state, mailbox);
  }
  Bytes info(const Bytes& body, size_t mailbox = 128) {
    return send(coe_message(next_counter(), 8, body), EsmState::PreOp, mailbox);
  }
  Bytes poll(size_t mailbox = 128) {
    Bytes reply(mailbox, 0xEE);
    reply.resize(server.poll(reply));
    return reply;
  }
  uint8_t next_counter() {
    master_counter = master_counter >= 7 ? 1 : master_counter + 1;
    return master_counter;
  }

  ObjectDictionary od;
  SdoServer server;
  uint8_t master_counter = 0;
};

// The reply after its 6-byte mailbox header (CoE header + body).
inline Bytes payload(const Bytes& reply) {
  return reply.size() < 6 ? Bytes{} : Bytes(reply.begin() + 6, reply.end());
}
inline uint16_t mailbox_length(const Bytes& reply) {
  return static_cast<uint16_t>(reply[0] | (reply[1] << 8));
}

// CoE header 0x3000 (SDO response) / 0x2000 (SDO request, used by aborts) little-endian.
inline Bytes abort_payload(uint16_t index, uint8_t sub, uint32_t code) {
  return {0x00,
          0x20,
          0x80,
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          static_cast<uint8_t>(code),
          static_cast<uint8_t>(code >> 8),
          static_cast<uint8_t>(code >> 16),
          static_cast<uint8_t>(code >> 24)};
}

// Upload / download request bodies (ETG.1000.6 Tables 35-40).
inline Bytes upload_req(uint16_t index, uint8_t sub, bool ca = false) {
  return {static_cast<uint8_t>(ca ? 0x50 : 0x40),
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          0,
          0,
          0,
          0};
}
inline Bytes download_expedited(uint16_t index, uint8_t sub, uint32_t value, size_t n,
                                bool ca = false) {
  return {static_cast<uint8_t>(0x23 | ((4 - n) << 2) | (ca ? 0x10 : 0)),
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          static_cast<uint8_t>(value),
          static_cast<uint8_t>(value >> 8),
          static_cast<uint8_t>(value >> 16),
          static_cast<uint8_t>(value >> 24)};
}
inline Bytes download_normal(uint16_t index, uint8_t sub, const Bytes& data, bool ca = false,
                             size_t announced = SIZE_MAX) {
  const uint32_t size = static_cast<uint32_t>(announced == SIZE_MAX ? data.size() : announced);
  Bytes b(8 + data.size());
  b[0] = static_cast<uint8_t>(0x21 | (ca ? 0x10 : 0));  // normal, size indicated
  b[1] = static_cast<uint8_t>(index);
  b[2] = static_cast<uint8_t>(index >> 8);
  b[3] = sub;
  for (int i = 0; i < 4; ++i) b[4 + i] = static_cast<uint8_t>(size >> (8 * i));
  std::copy(data.begin(), data.end(), b.begin() + 8);
  return b;
}
inline Bytes download_ok(uint16_t index, uint8_t sub, bool ca = false) {
  return {0x00,
          0x30,
          static_cast<uint8_t>(ca ? 0x70 : 0x60),
          static_cast<uint8_t>(index),
          static_cast<uint8_t>(index >> 8),
          sub,
          0,
          0,
          0,
          0};
}

}  // namespace rackcat::coe::test
