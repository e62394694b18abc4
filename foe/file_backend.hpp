// What the FoE server needs from the device behind it: a small file system of named files with
// a password, read whole and written in order, then committed. The FoE server (foe_server.hpp)
// owns the protocol (packet numbers, last-packet rule, busy, errors, timeouts); the backend
// owns names, access rules per ESM state, verification and storage. Every refusal is an FoE
// error code (foe_error.hpp), sent to the master as it is.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "foe/foe_error.hpp"

namespace rackcat::foe {

// Where a commit stands (ETG.1000.6 §5.8 "Busy": Done of Entire).
struct CommitProgress {
  bool busy = false;                // still committing: the server answers Busy
  FoeError error = FoeError::None;  // when not busy: None = committed, else the refusal
  uint16_t done = 0;                // progress for the Busy request's Done / Entire fields
  uint16_t entire = 0;
};

// Where a read request stands: the file is in `contents` (error None), refused (error), or
// still being fetched off the device thread (busy).
struct ReadProgress {
  bool busy = false;
  FoeError error = FoeError::None;
};

class FileBackend {
 public:
  virtual ~FileBackend() = default;

  // Read request: the whole file into `contents` (at most `max_size` bytes), or the refusal.
  // A backend that reads its files elsewhere answers busy; then poll_read() is called (the
  // mailbox poll) until it is not, and the server's first Data goes out only then: the read
  // request's reply is deferred, not a Busy (ETG.1000.6 §5.8 has Busy answer a write's Data;
  // SOEM's FOEread, for one, fails on a Busy in a read).
  virtual ReadProgress read_file(std::string_view name, uint32_t password, size_t max_size,
                                 std::vector<uint8_t>& contents) = 0;
  virtual ReadProgress poll_read(std::vector<uint8_t>& /*contents*/) {
    return {false, FoeError::NotDefined};
  }
  // The pending read is abandoned (a new request, a timeout, the mailbox restarted).
  virtual void abort_read() {}
  // Write request: name, password and state checked, a write prepared (nothing visible yet).
  virtual FoeError begin_write(std::string_view name, uint32_t password) = 0;
  // The next data bytes of the open write, in order.
  virtual FoeError write_data(std::span<const uint8_t> data) = 0;
  // The last packet arrived: verify and commit the file. May return busy; then poll_commit()
  // is called until it is not. A refused file leaves the stored one unchanged.
  virtual CommitProgress commit() = 0;
  virtual CommitProgress poll_commit() = 0;
  // The open write is abandoned (error, timeout, a new request): drop what was received.
  virtual void abort_write() = 0;
};

}  // namespace rackcat::foe
