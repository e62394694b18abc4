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

class FileBackend {
 public:
  virtual ~FileBackend() = default;

  // Read request: the whole file into `contents` (at most `max_size` bytes), or the refusal.
  virtual FoeError read_file(std::string_view name, uint32_t password, size_t max_size,
                             std::vector<uint8_t>& contents) = 0;
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
