// Uses the installed CoE layer alone: one object, one SDO upload of it (ETG.1000.6 §5.6.2.2,
// expedited upload of 0x1000:00, the CoE data of one mailbox message). Exit 0 when the reply
// carries the value.
#include <array>
#include <cstdio>

#include "coe/access.hpp"
#include "coe/data_type.hpp"
#include "coe/object_dictionary.hpp"
#include "coe/sdo_server.hpp"

int main() {
  using namespace rackcat;
  coe::ObjectDictionary od;
  coe::Object o(0x1000, coe::ObjectCode::Var, "Device type",
                static_cast<uint16_t>(coe::DataType::Unsigned32));
  o.add(coe::make_entry(0, "Device type", coe::DataType::Unsigned32, 32, coe::access::kRo,
                        {0x91, 0x01, 0x0F, 0x00}));
  od.add(std::move(o));
  coe::SdoServer sdo(od);
  // CoE header (SDO request), upload initiate 0x40 of 0x1000:00.
  const std::array<uint8_t, 10> request{0x00, 0x20, 0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0};
  std::array<uint8_t, 122> reply{};
  const size_t n = sdo.handle(request, reply, EsmState::PreOp).length;
  if (n < 10 || reply[6] != 0x91 || reply[7] != 0x01 || reply[8] != 0x0F) {
    std::fprintf(stderr, "coe_only: unexpected SDO reply (%zu bytes)\n", n);
    return 1;
  }
  std::printf("coe_only: 0x1000:00 = 0x%02x%02x%02x%02x\n", reply[9], reply[8], reply[7], reply[6]);
  return 0;
}
