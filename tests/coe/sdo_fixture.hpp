// A slave's SDO server on the test dictionary, with helpers that frame requests the way a
// master does (ETG.1000.4 §5.6 mailbox header, ETG.1000.6 §5.6.1 CoE header) and replies the
// way the firmware's MailboxServer does (tests/support/mailbox_framing.hpp).
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "coe/sdo_server.hpp"
#include "tests/coe/test_dictionary.hpp"
#include "tests/support/coe_frames.hpp"
#include "tests/support/mailbox_framing.hpp"

namespace rackcat::coe::test {

using testing::abort_payload;
using testing::Bytes;
using testing::coe_message;
using testing::download_expedited;
using testing::download_normal;
using testing::download_ok;
using testing::upload_req;

class SdoTest : public ::testing::Test {
 protected:
  SdoTest() : od(make_test_dictionary()), server(od) {}

  // Sends one request (next master counter 1..7) and returns the reply mailbox.
  Bytes send(const Bytes& message, EsmState state = EsmState::PreOp, size_t mailbox = 128) {
    Bytes reply(mailbox, 0xEE);
    reply.resize(frame.request(message, reply, [&](auto data, size_t, auto out) {
      return server.handle(data, out, state);
    }));
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
    reply.resize(frame.poll(reply, [&](auto out) { return server.poll(out); }));
    return reply;
  }
  uint8_t next_counter() {
    master_counter = master_counter >= 7 ? 1 : master_counter + 1;
    return master_counter;
  }

  ObjectDictionary od;
  SdoServer server;
  rackcat::testing::SlaveMailbox frame;
  uint8_t master_counter = 0;
};

// The reply after its 6-byte mailbox header (CoE header + body).
inline Bytes payload(const Bytes& reply) {
  return reply.size() < 6 ? Bytes{} : Bytes(reply.begin() + 6, reply.end());
}
inline uint16_t mailbox_length(const Bytes& reply) {
  return static_cast<uint16_t>(reply[0] | (reply[1] << 8));
}

}  // namespace rackcat::coe::test
