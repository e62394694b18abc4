// SDO over CAN, client side (CiA 301 §7.2.4.3): the control module reads a RIM's identity and
// card list. Upload only, expedited or segmented; the command bytes are coe::sdo's constants
// (the same protocol the CoE server speaks). Non-blocking: start_upload() gives the request
// frame, on_frame() consumes responses and gives the next request, poll() times out.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "coe/abort_code.hpp"
#include "modules/canopen/frame.hpp"

namespace rackcat::modules::canopen {

class SdoClient {
 public:
  enum class Status : uint8_t { Idle, Busy, Done, Aborted, TimedOut };

  SdoClient(uint8_t node_id, Micros timeout_us, size_t max_size = 4096)
      : node_(node_id), timeout_(timeout_us), max_size_(max_size) {}

  // Starts reading index:subindex; `out` is the initiate request to send.
  CanFrame start_upload(uint16_t index, uint8_t subindex, Micros now);
  // A frame from the bus. True when it belonged to the running transfer; `next` then holds a
  // frame to send when `has_next` (the next segment request, or an abort of ours).
  bool on_frame(const CanFrame& frame, Micros now, CanFrame& next, bool& has_next);
  // The server did not answer in time: status TimedOut, `abort` is the abort frame to send
  // (0x05040000 SDO protocol timed out). False while nothing timed out.
  bool poll(Micros now, CanFrame& abort);

  Status status() const { return status_; }
  const std::vector<uint8_t>& data() const { return data_; }
  coe::AbortCode abort_code() const { return abort_code_; }
  uint16_t index() const { return index_; }
  uint8_t subindex() const { return subindex_; }

 private:
  CanFrame make_abort(coe::AbortCode code);
  void fail(coe::AbortCode code) {
    status_ = Status::Aborted;
    abort_code_ = code;
  }

  uint8_t node_;
  Micros timeout_;
  size_t max_size_;
  Status status_ = Status::Idle;
  uint16_t index_ = 0;
  uint8_t subindex_ = 0;
  bool segmented_ = false;
  uint8_t toggle_ = 0;
  size_t expected_ = 0;  // size indicated by the server (0 = not indicated)
  Micros deadline_ = 0;
  std::vector<uint8_t> data_;
  coe::AbortCode abort_code_ = coe::AbortCode::None;
};

}  // namespace rackcat::modules::canopen
