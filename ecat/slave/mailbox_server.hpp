// The slave's mailbox (ETG.1000.4 §5.6, §6.7.3; ETG.1000.6 §5.2): SM0 carries the master's
// requests, SM1 the slave's replies and unsolicited messages. The server owns what every
// protocol shares and none should repeat:
//   - the frame: the mailbox header of every request is read here and of every message sent
//     written here (base/mailbox_header.hpp); a protocol sees only the data after it;
//   - the header check: a Length that does not fit SM0 is answered with mailbox error 0x0008
//     (invalid size), a channel other than 0 with 0x0003, a Type no registered protocol
//     serves in the current state with 0x0002 (unsupported protocol) (ETG.1000.6 §5.2.3
//     Table 29); a protocol's own header errors (0x0004..0x0007) go out as error replies too;
//   - double writes: a request repeating the previous request's non-zero counter and bytes is
//     the master resending a write whose working counter it missed; it is dropped (no reply,
//     not executed twice) (ETG.1000.4 §5.6, header "Cnt");
//   - the counter of every message the slave sends, 1..7 wrapping to 1;
//   - the repeat request: when the master toggles SM1's repeat bit (0x080E bit 1) the last
//     message goes into SM1 again and the slave toggles the acknowledge (0x080F bit 1)
//     (ETG.1000.4 §6.7.3);
//   - dispatch by Type to the registered protocols, and polling them for unsolicited
//     messages whenever SM1 is free.
// It reaches SM0/SM1 only through the PDI. Buffers are sized at start(); the rest never
// allocates.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/esm_state.hpp"
#include "base/mailbox_error.hpp"
#include "base/mailbox_header.hpp"
#include "ecat/pdi_port.hpp"
#include "ecat/slave/esm_observer.hpp"
#include "ecat/slave/mailbox_protocol.hpp"

namespace rackcat::ecat {

class MailboxServer {
 public:
  static constexpr size_t kMaxProtocols = 8;
  static constexpr size_t kHeaderSize = mailbox::Header::kSize;

  // States a protocol serves (bit per state); CoE: PREOP, SAFEOP, OP (ETG.1000.6 §5.3); a
  // bootstrap protocol (FoE in BOOT) registers for kBoot.
  static constexpr uint8_t kPreOp = 0x01;
  static constexpr uint8_t kSafeOp = 0x02;
  static constexpr uint8_t kOp = 0x04;
  static constexpr uint8_t kBoot = 0x08;
  static constexpr uint8_t kMailboxStates = kPreOp | kSafeOp | kOp;

  explicit MailboxServer(PdiPort& pdi) : pdi_(pdi) {}

  // Registers `protocol` for mailbox `type` in `states`. A later registration for the same
  // type replaces the earlier one. Start-up only; false when the table is full.
  bool add(mailbox::Type type, MailboxProtocol& protocol, uint8_t states = kMailboxStates);

  // The mailbox opens with SM0 at `in_start`/`in_length` and SM1 at `out_start`/`out_length`
  // (the ESM checked them against the SII). Sizes the buffers (transition only, not cyclic).
  void start(uint16_t in_start, uint16_t in_length, uint16_t out_start, uint16_t out_length);
  // The mailbox closes (INIT): protocols reset, no last message to repeat, the master's next
  // counter starts a new sequence.
  void stop();
  bool running() const { return running_; }

  // One pass: a request waiting in SM0 is read (which frees SM0) and answered; a repeat
  // request is served; with SM1 free, a protocol's unsolicited message goes out.
  // `sm0_written`: AL event bit 8 or SM0's status says the master completed a write.
  void service(EsmState state, bool sm0_written, bool activation_changed);

  uint8_t last_counter() const { return counter_; }
  // Hears every mailbox error reply the server sends (its header checks and the protocols'
  // errors alike); nullptr removes it.
  void set_observer(EsmObserver* observer) { observer_ = observer; }

 private:
  struct Entry {
    uint8_t type = 0;
    uint8_t states = 0;
    MailboxProtocol* protocol = nullptr;
  };
  static uint8_t state_bit(EsmState s);
  const Entry* find(uint8_t type, EsmState state) const;
  size_t dispatch(std::span<const uint8_t> request, EsmState state);
  size_t mailbox_error(mailbox::Error error, uint16_t address);
  size_t frame(const Entry& entry, size_t data_length);
  bool sm1_free();
  void send(size_t length);
  void serve_repeat();

  // running_ first: the firmware asks for it on every cyclic frame (Firmware::wants_service),
  // the rest only when the mailbox has work.
  bool running_ = false;
  PdiPort& pdi_;
  EsmObserver* observer_ = nullptr;
  std::array<Entry, kMaxProtocols> protocols_{};
  size_t protocol_count_ = 0;
  uint16_t in_start_ = 0, in_length_ = 0, out_start_ = 0, out_length_ = 0;

  std::vector<uint8_t> request_;  // SM0 as read
  std::vector<uint8_t> reply_;    // the message being built for SM1
  std::vector<uint8_t> last_;     // the last message sent, for a repeat request
  size_t last_len_ = 0;

  uint8_t counter_ = 0;  // our last counter (1..7)
  uint8_t last_request_counter_ = 0;
  std::vector<uint8_t> last_request_;
  size_t last_request_len_ = 0;
  size_t next_poll_ = 0;  // round robin over the protocols for unsolicited messages
};

}  // namespace rackcat::ecat
