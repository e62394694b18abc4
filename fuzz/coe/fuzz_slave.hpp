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

// Every reply must fit the mailbox and carry a consistent header; anything else is a bug.
inline void check_reply(std::span<const uint8_t> reply, size_t n) {
  if (n == 0) return;
  if (n > reply.size() || n < 10) std::abort();
  const size_t len = static_cast<size_t>(reply[0] | (reply[1] << 8));
  if (len + 6 != n) std::abort();
  const uint8_t type = reply[5] & 0x0F;
  const uint8_t counter = (reply[5] >> 4) & 0x07;
  if ((type != 0x00 && type != 0x03) || counter == 0) std::abort();
}

inline EsmState state_of(uint8_t b) {
  constexpr EsmState kStates[] = {EsmState::PreOp, EsmState::SafeOp, EsmState::Op, EsmState::Init,
                                  EsmState::Boot};
  return kStates[b % 5];
}

}  // namespace rackcat::coe::fuzz
