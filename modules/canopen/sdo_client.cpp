#include "modules/canopen/sdo_client.hpp"

#include "coe/bits.hpp"
#include "coe/sdo_command.hpp"

namespace rackcat::modules::canopen {

namespace sdo = coe::sdo;

CanFrame SdoClient::start_upload(uint16_t index, uint8_t subindex, Micros now) {
  status_ = Status::Busy;
  index_ = index;
  subindex_ = subindex;
  segmented_ = false;
  toggle_ = 0;
  expected_ = 0;
  data_.clear();
  abort_code_ = coe::AbortCode::None;
  deadline_ = now + timeout_;
  // Initiate upload request (CiA 301 §7.2.4.3.6): ccs = 2, index, subindex, 4 reserved.
  std::array<uint8_t, 8> b{static_cast<uint8_t>(sdo::kCcsUploadInitiate << 5)};
  le::put16(&b[1], index);
  b[3] = subindex;
  return CanFrame::make(cob::kSdoRx + node_, b);
}

CanFrame SdoClient::make_abort(coe::AbortCode code) {
  std::array<uint8_t, 8> b{sdo::kAbortCommand};
  le::put16(&b[1], index_);
  b[3] = subindex_;
  le::put32(&b[4], static_cast<uint32_t>(code));
  return CanFrame::make(cob::kSdoRx + node_, b);
}

bool SdoClient::on_frame(const CanFrame& f, Micros now, CanFrame& next, bool& has_next) {
  has_next = false;
  if (status_ != Status::Busy || f.id != cob::kSdoTx + node_) {
    return false;
  }
  if (f.len != 8) {
    fail(coe::AbortCode::CommandSpecifier);
    next = make_abort(abort_code_);
    has_next = true;
    return true;
  }
  const uint8_t cmd = f.data[0];
  if (cmd == sdo::kAbortCommand) {
    status_ = Status::Aborted;
    abort_code_ = static_cast<coe::AbortCode>(le::get32(&f.data[4]));
    return true;
  }
  deadline_ = now + timeout_;
  if (!segmented_) {
    if (sdo::specifier(cmd) != sdo::kScsUploadInitiate || le::get16(&f.data[1]) != index_ ||
        f.data[3] != subindex_) {
      fail(coe::AbortCode::CommandSpecifier);
      next = make_abort(abort_code_);
      has_next = true;
      return true;
    }
    if (cmd & sdo::kExpedited) {
      // Expedited (CiA 301 §7.2.4.3.7): n = 4 - bits 3..2 when the size is indicated.
      const size_t n = (cmd & sdo::kSizeIndicated) ? 4 - ((cmd >> 2) & 0x03) : 4;
      data_.assign(f.data.begin() + 4, f.data.begin() + 4 + n);
      status_ = Status::Done;
      return true;
    }
    expected_ = (cmd & sdo::kSizeIndicated) ? le::get32(&f.data[4]) : 0;
    if (expected_ > max_size_) {
      fail(coe::AbortCode::OutOfMemory);
      next = make_abort(abort_code_);
      has_next = true;
      return true;
    }
    segmented_ = true;
  } else {
    // Upload segment response (CiA 301 §7.2.4.3.9): toggle must match our request.
    if (sdo::specifier(cmd) != sdo::kScsUploadSegment) {
      fail(coe::AbortCode::CommandSpecifier);
      next = make_abort(abort_code_);
      has_next = true;
      return true;
    }
    if ((cmd & sdo::kToggle) != toggle_) {
      fail(coe::AbortCode::ToggleBit);
      next = make_abort(abort_code_);
      has_next = true;
      return true;
    }
    const size_t n = 7 - ((cmd >> 1) & 0x07);
    if (data_.size() + n > max_size_) {
      fail(coe::AbortCode::OutOfMemory);
      next = make_abort(abort_code_);
      has_next = true;
      return true;
    }
    data_.insert(data_.end(), f.data.begin() + 1, f.data.begin() + 1 + n);
    toggle_ ^= sdo::kToggle;
    if (cmd & sdo::kLastSegment) {
      if (expected_ != 0 && data_.size() != expected_) {
        fail(coe::AbortCode::LengthMismatch);
        next = make_abort(abort_code_);
        has_next = true;
        return true;
      }
      status_ = Status::Done;
      return true;
    }
  }
  // Upload segment request: ccs = 3 with the toggle bit.
  std::array<uint8_t, 8> b{static_cast<uint8_t>((sdo::kCcsUploadSegment << 5) | toggle_)};
  next = CanFrame::make(cob::kSdoRx + node_, b);
  has_next = true;
  return true;
}

bool SdoClient::poll(Micros now, CanFrame& abort) {
  if (status_ != Status::Busy || now < deadline_) {
    return false;
  }
  status_ = Status::TimedOut;
  abort_code_ = coe::AbortCode::Timeout;
  abort = make_abort(abort_code_);
  return true;
}

}  // namespace rackcat::modules::canopen
