// SDO Information: the input is the SDO Information body (opcode, reserved, fragments left,
// request data) behind a correct CoE header; byte 0 picks the reply size (SM1 minus the
// mailbox header). All
// fragments are collected and checked: fragments-left counts down to 0 and a list response is
// whole 16-bit words.
#include <vector>

#include "coe/bits.hpp"
#include "fuzz/coe/fuzz_slave.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rackcat::coe;
  namespace le = rackcat::le;
  if (size < 1 || size > 200) return 0;
  fuzz::Slave& s = fuzz::slave();
  std::vector<uint8_t> reply(10 + data[0] % 120);
  const size_t body = size - 1;
  std::vector<uint8_t> request(2 + body);
  request[1] = 0x80;  // CoE header: SDO Information
  std::copy(data + 1, data + size, request.begin() + 2);

  const rackcat::mailbox::Answer answer = s.server.handle(request, reply, rackcat::EsmState::PreOp);
  fuzz::check_reply(reply, answer);
  size_t n = answer.length;
  int expected_left = -1;
  while (n) {
    if ((reply[1] >> 4) != 8) break;  // another service
    const uint16_t left = le::get16(&reply[4]);
    const bool incomplete = (reply[2] & 0x80) != 0;
    if (expected_left >= 0 && left != expected_left) std::abort();
    if (incomplete != (left != 0)) std::abort();
    if ((reply[2] & 0x7F) == 0x02 && (n - 6) % 2 != 0) std::abort();
    if (!incomplete) break;
    expected_left = left - 1;
    n = s.server.poll(reply);
    fuzz::check_reply(reply, n);
    if (n == 0) std::abort();  // fragments announced but none delivered
  }
  return 0;
}
