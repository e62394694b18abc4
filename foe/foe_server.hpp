// The FoE server of one slave (ETG.1000.5 §6.4, ETG.1000.6 §5.8 "File Access over EtherCAT"):
// takes the FoE part of a mailbox request (FoE header and what follows, no mailbox header) and
// writes the FoE part of the reply. The mailbox layer (header, counter, repeat, double writes)
// and the files (FileBackend) are outside.
//
// Services:
// - Read request (password, file name) -> Data 1..n, each acknowledged by the master (Ack n)
//   before Data n+1; a Data shorter than the reply mailbox allows is the last one (a file of
//   an exact multiple ends with an empty Data). A backend that fetches the file off the device
//   thread defers the reply: Data 1 (or the Error) is then sent by poll() once it is there.
// - Write request (password, file name) -> Ack 0; Data n (n = previous + 1) -> Ack n; the
//   Data shorter than the request mailbox allows is the last: the file is committed, and while
//   the commit runs every repeat of that Data gets Busy (Done, Entire), then Ack n or an Error.
//   A repeated Data n (the master's resend) is acknowledged again, not written twice.
// - Error request from the master ends the transfer, no reply. Anything out of turn (Data or
//   Ack without a transfer, Busy from the master, an unknown OpCode) is answered Error 0x8004.
// - A new read or write request ends a stale transfer; a transfer idle for longer than
//   `transfer_timeout_ms` is dropped (its partial file discarded).
// Every Error carries the code and its standard text (foe_error.hpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "base/mailbox_error.hpp"
#include "foe/file_backend.hpp"
#include "foe/foe_error.hpp"
#include "foe/foe_header.hpp"

namespace rackcat::foe {

struct FoeLimits {
  size_t max_name_length = 64;               // longer names: Error 0x8004 Illegal
  size_t max_file_size = 16u * 1024 * 1024;  // more data: Error 0x8003 Disk full
  uint32_t transfer_timeout_ms = 10'000;     // no request for this long: the transfer is dropped
};

class FoeServer {
 public:
  using Clock = std::function<uint64_t()>;  // monotonic milliseconds

  struct Result {
    size_t length = 0;       // bytes of FoE reply written (0: no reply)
    bool too_short = false;  // the request is shorter than an FoE header: mailbox error 0x0006
  };

  // `backend` must outlive the server. `clock` defaults to std::chrono::steady_clock.
  explicit FoeServer(FileBackend& backend, FoeLimits limits = {}, Clock clock = {});

  // One FoE request -> at most one FoE reply. `request` is the FoE header plus data (the
  // mailbox data); `request_capacity` the most mailbox data the receive mailbox (SM0) can hold,
  // which sets the last-packet rule of writes; `reply` the send mailbox's data part (SM1 size
  // minus the mailbox header), which sets the data size of reads.
  Result handle(std::span<const uint8_t> request, size_t request_capacity,
                std::span<uint8_t> reply);
  // handle() as a device's FoE mailbox protocol answers (ecat::MailboxProtocol::on_request):
  // a send mailbox too small for an FoE header is mailbox error 0x0007, a request shorter than
  // one 0x0006 (ETG.1000.6 §5.2.3 Table 29); otherwise the reply's length.
  mailbox::Answer handle_mailbox(std::span<const uint8_t> request, size_t request_capacity,
                                 std::span<uint8_t> reply);

  // Drops a transfer idle past its timeout and drives a finished commit to its end. Call now
  // and then (the mailbox poll).
  void tick();
  // tick(), and the deferred reply of a read request whose file the backend fetched in the
  // meantime (its first Data or the Error; 0: nothing to send). `reply` as for handle(). Call
  // whenever the send mailbox is free (ecat::MailboxProtocol::poll).
  size_t poll(std::span<uint8_t> reply);
  // The mailbox restarted (ESM back to INIT): any transfer ends; a running commit completes on
  // its own (never waited for here).
  void reset();

  bool idle() const { return phase_ == Phase::Idle; }
  bool committing() const { return phase_ == Phase::Committing; }

 private:
  // Opening: a read request waits for its file (the backend's poll_read).
  enum class Phase : uint8_t { Idle, Opening, Reading, Writing, Committing };

  size_t read_request(std::span<const uint8_t> name, uint32_t password, std::span<uint8_t> reply);
  size_t write_request(std::span<const uint8_t> name, uint32_t password, std::span<uint8_t> reply);
  size_t data(uint32_t packet, std::span<const uint8_t> bytes, size_t max_data,
              std::span<uint8_t> reply);
  size_t ack(uint32_t packet, std::span<uint8_t> reply);
  // The read request's file is there (e None) or refused: the first Data or the Error.
  size_t opened(FoeError e, std::span<uint8_t> reply);
  size_t send_data(std::span<uint8_t> reply);
  size_t progress_reply(const CommitProgress& p, std::span<uint8_t> reply);
  size_t error(FoeError code, std::span<uint8_t> reply);
  size_t simple(OpCode op, uint32_t value, std::span<uint8_t> reply);
  // Ends the current transfer (abort_write for a write).
  void end_transfer();
  bool name_of(std::span<const uint8_t> raw, std::string& name) const;

  FileBackend& backend_;
  FoeLimits limits_;
  Clock clock_;
  Phase phase_ = Phase::Idle;
  uint32_t packet_ = 0;   // last packet sent (read) or received (write)
  size_t offset_ = 0;     // read: bytes of the file sent before the current packet
  size_t last_sent_ = 0;  // read: data bytes in the current packet
  size_t last_max_ = 0;   // read: the most a packet could carry when it was sent
  size_t received_ = 0;   // write: bytes written so far
  uint64_t last_activity_ = 0;
  std::vector<uint8_t> file_;  // read: the file being sent
  std::string name_;
};

}  // namespace rackcat::foe
