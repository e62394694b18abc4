// A slave shared by the CoE fuzz targets: a dictionary with every object shape the SDO server
// handles (VAR, ARRAY, RECORD with bits and gaps, strings, enums, limits, PDO objects with the
// generic validators), persisting across inputs so segmented and fragmented state is explored.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <span>

#include "coe/pdo_mapping.hpp"
#include "coe/sdo_server.hpp"
#include "tests/coe/test_dictionary.hpp"

namespace rackcat::coe::fuzz {

struct Slave {
  ObjectDictionary od;
  SdoServer server;
  Slave() : od(make()), server(od) {}
  static ObjectDictionary make() {
    ObjectDictionary od = test::make_test_dictionary();
    install_pdo_validators(od, 32, 32);
    return od;
  }
};

inline Slave& slave() {
  static Slave s;
  return s;
}

// Every reply must fit the mailbox data and carry a CoE header with a service a slave sends
// (Emergency 1, SDO request 2 = abort, SDO response 3, SDO Information 8); a mailbox error is
// the only other answer. Anything else is a bug.
inline void check_reply(std::span<const uint8_t> reply, size_t n,
                        mailbox::Error error = mailbox::Error::None) {
  if (error != mailbox::Error::None) {
    if (n != 0) std::abort();
    return;
  }
  if (n == 0) return;
  if (n > reply.size() || n < 4) std::abort();
  const uint8_t service = reply[1] >> 4;
  if (service != 1 && service != 2 && service != 3 && service != 8) std::abort();
}
inline void check_reply(std::span<const uint8_t> reply, mailbox::Answer a) {
  check_reply(reply, a.length, a.error);
}

inline EsmState state_of(uint8_t b) {
  constexpr EsmState kStates[] = {EsmState::PreOp, EsmState::SafeOp, EsmState::Op, EsmState::Init,
                                  EsmState::Boot};
  return kStates[b % 5];
}

}  // namespace rackcat::coe::fuzz
