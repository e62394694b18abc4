// Whole Ethernet frames into a 3-slave segment whose state persists across inputs, so the
// fuzzer walks the ESM, mailbox, SII, FMMU/SM and DC state together. Input byte 0 advances the
// manual clock (x 50 µs: SYNC events and watchdogs fire), the rest is the frame. The reply
// must come back at full length (or 0 for non-EtherCAT frames) and nothing may crash.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "ecat/segment.hpp"
#include "tests/ecat/test_application.hpp"

namespace {

using namespace rackcat::ecat;
using rackcat::EsmState;

// A device that accepts everything and records nothing (state persists for millions of runs).
class FuzzDevice final : public Application, public MailboxProtocol {
 public:
  std::span<const uint8_t> eeprom() const override { return sii_; }
  uint16_t on_state_request(EsmState, EsmState to) override {
    return to == EsmState::Op && (++n_ % 7 == 0) ? 0x001A : 0;
  }
  void on_state_changed(EsmState, EsmState) override {}
  ProcessDataSizes process_data_sizes() const override {
    return {test::kOutputBytes, test::kInputBytes};
  }
  void add_mailbox_protocols(MailboxServer& server) override {
    server.add(rackcat::mailbox::Type::CoE, *this);
  }
  rackcat::mailbox::Answer on_request(const MailboxRequest& request,
                                      std::span<uint8_t> reply) override {
    const size_t n = std::min(request.data.size(), reply.size());
    std::copy_n(request.data.begin(), n, reply.begin());
    if (n == 0) return {0, rackcat::mailbox::Error::SizeTooShort};
    return {n, rackcat::mailbox::Error::None};
  }
  size_t poll(std::span<uint8_t> reply) override {
    if (++n_ % 13 != 0 || reply.size() < 8) return 0;
    std::fill_n(reply.begin(), 8, uint8_t{0x5A});
    return 8;
  }
  bool update_inputs(std::span<uint8_t> inputs) override {
    std::fill(inputs.begin(), inputs.end(), uint8_t(n_));
    return true;
  }
  void on_outputs(std::span<const uint8_t> outputs) override {
    last_ = outputs.empty() ? 0 : outputs[0];
  }

 private:
  std::vector<uint8_t> sii_ = test::make_test_sii();
  unsigned n_ = 0;
  uint8_t last_ = 0;
};

struct World {
  ManualClock clock;
  std::array<FuzzDevice, 3> devices;
  Segment segment{{&devices[0], &devices[1], &devices[2]}, clock};
  std::array<uint8_t, 0xFFFF> frame{};
};

World& world() {
  static World w;
  return w;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  World& w = world();
  w.clock.advance(static_cast<uint64_t>(data[0]) * 50'000);
  w.segment.service();
  const size_t n = std::min(size - 1, w.frame.size());
  std::memcpy(w.frame.data(), data + 1, n);
  const size_t reply = w.segment.process(std::span<uint8_t>(w.frame.data(), n));
  if (reply != 0 && reply != n) std::abort();  // a frame is answered at full length or not at all
  w.segment.after_frame();  // the firmware, once the reply is out (as the event loop does)
  for (size_t k = 0; k < w.segment.size(); ++k) {
    // The AL status register always holds a valid state (ETG.1000.6 Table 9).
    const uint8_t state = w.segment.slave(k).esc().read8(0x0130) & 0x0F;
    if (state != 1 && state != 2 && state != 3 && state != 4 && state != 8) std::abort();
  }
  return 0;
}
