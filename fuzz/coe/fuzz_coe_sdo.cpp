// Feeds raw CoE mailbox data (what the firmware hands the CoE protocol) to one persistent SDO
// server. Input: byte 0 = ESM state, byte 1 = reply size (10..265), then messages as [length
// byte][bytes]; after each, queued messages are drained with poll(). Checks every reply
// against the CoE header rules.
#include <vector>

#include "fuzz/coe/fuzz_slave.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rackcat::coe;
  if (size < 2) return 0;
  fuzz::Slave& s = fuzz::slave();
  const rackcat::EsmState state = fuzz::state_of(data[0]);
  std::vector<uint8_t> reply(10 + data[1]);
  size_t pos = 2;
  while (pos < size) {
    const size_t len = std::min<size_t>(data[pos], size - pos - 1);
    const std::span<const uint8_t> request(data + pos + 1, len);
    pos += 1 + len;
    fuzz::check_reply(reply, s.server.handle(request, reply, state));
    for (int i = 0; i < 64; ++i) {
      const size_t n = s.server.poll(reply);
      fuzz::check_reply(reply, n);
      if (!n) break;
    }
  }
  return 0;
}
