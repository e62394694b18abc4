// SDO download: expedited, normal and segmented, single entry or complete access
// (ETG.1000.6 §5.6.2.1 - §5.6.2.3). Every write is checked (access per ESM state, length,
// value range, the object's validate_write hook) before one byte of the image changes.
#include <algorithm>
#include <array>
#include <cstring>

#include "coe/bits.hpp"
#include "coe/coe_header.hpp"
#include "coe/complete_access.hpp"
#include "coe/entry_check.hpp"
#include "coe/sdo_command.hpp"
#include "coe/sdo_server.hpp"

namespace rackcat::coe {
namespace {
constexpr size_t kBodyOffset = CoeHeader::kSize;
constexpr uint8_t kResponse = static_cast<uint8_t>(CoeService::SdoResponse);
}  // namespace

AbortCode SdoServer::check_download_target(const Object& obj, uint8_t subindex, bool ca,
                                           size_t size, EsmState state) const {
  if (ca) {
    if (obj.code() == ObjectCode::Var) {
      return AbortCode::CompleteAccessUnsupported;
    }
    if (subindex > 1) {
      return AbortCode::UnsupportedAccess;
    }
    if (size > ca_bytes(obj, subindex, obj.max_subindex())) {
      return AbortCode::LengthTooHigh;
    }
    // Some entry must be writable now; the per-entry check follows with the data.
    uint16_t writable = 0;
    for (const Entry& e : obj.entries()) {
      if (e.subindex >= subindex && !e.padding) {
        writable |= e.access;
      }
    }
    return check_write_access(writable, state);
  }
  const Entry* e = obj.entry(subindex);
  if (!e || e->padding) {
    return AbortCode::SubindexNotFound;
  }
  if (AbortCode rc = check_write_access(e->access, state); rc != AbortCode::None) {
    return rc;
  }
  if (size > e->byte_length()) {
    return AbortCode::LengthTooHigh;
  }
  if (size < e->byte_length() && e->type() != DataType::VisibleString) {
    return AbortCode::LengthTooLow;
  }
  return AbortCode::None;
}

AbortCode SdoServer::write_entry(Object& obj, const Entry& e, std::span<const uint8_t> data,
                                 EsmState state) {
  if (AbortCode rc = check_write_access(e.access, state); rc != AbortCode::None) {
    return rc;
  }
  const size_t len = e.byte_length();
  if (data.size() > len) {
    return AbortCode::LengthTooHigh;
  }
  // A shorter VISIBLE_STRING is a shorter text: the rest of the entry is padded with 0.
  if (data.size() < len && e.type() != DataType::VisibleString) {
    return AbortCode::LengthTooLow;
  }
  if (len > capacity_) {
    return AbortCode::OutOfMemory;  // buffers sized by prepare()
  }
  std::array<uint8_t, kStackScratch> local;  // written before it is read
  uint8_t* value = len <= local.size() ? local.data() : scratch_.data();
  std::memmove(value, data.data(), data.size());
  std::memset(value + data.size(), 0, len - data.size());
  const std::span<const uint8_t> v(value, len);
  if (AbortCode rc = check_value(od_, obj, e, v, obj.image()); rc != AbortCode::None) {
    return rc;
  }
  const int subindex = e.subindex;
  if (obj.hooks().validate_write) {
    if (AbortCode rc = obj.hooks().validate_write(obj, subindex, v, state); rc != AbortCode::None) {
      return rc;
    }
  }
  copy_bits(obj.image().data(), e.bit_offset, value, 0, e.bit_length);
  if (obj.hooks().after_write) {
    obj.hooks().after_write(obj, subindex);
  }
  return AbortCode::None;
}

AbortCode SdoServer::commit_download(Object& obj, uint8_t subindex, bool ca,
                                     std::span<const uint8_t> data, EsmState state) {
  if (ca) {
    return write_complete(obj, subindex, data, state);
  }
  const Entry* e = obj.entry(subindex);
  if (!e || e->padding) {
    return AbortCode::SubindexNotFound;
  }
  return write_entry(obj, *e, data, state);
}

size_t SdoServer::download_initiate(std::span<const uint8_t> body, std::span<uint8_t> reply,
                                    EsmState state) {
  const auto [cmd, index, subindex, ca, obj] = begin_initiate(body);
  if (!obj) {
    return abort(reply, index, subindex, missing_object());
  }

  AbortCode rc = AbortCode::None;
  if (cmd & sdo::kExpedited) {
    // Expedited (Table 35): up to 4 bytes in the request; without the size indicator the
    // entry's own length applies (at most 4).
    size_t size = 4;
    if (cmd & sdo::kSizeIndicated) {
      size = 4 - ((cmd >> 2) & 0x03);
    } else if (!ca) {
      if (const Entry* e = obj->entry(subindex)) {
        size = std::min<size_t>(4, e->byte_length());
      }
    }
    rc = commit_download(*obj, subindex, ca, body.subspan(4, size), state);
  } else {
    // Normal (Table 36): complete size, then the data; more than fits follows in segments.
    const size_t in_frame = body.size() - sdo::kInitiateBody;
    const size_t size = (cmd & sdo::kSizeIndicated) ? le::get32(&body[4]) : in_frame;
    if (in_frame >= size) {
      rc = commit_download(*obj, subindex, ca, body.subspan(sdo::kInitiateBody, size), state);
    } else {
      rc = check_download_target(*obj, subindex, ca, size, state);
      if (rc == AbortCode::None && size > data_.size()) {
        rc = AbortCode::OutOfMemory;
      }
      if (rc == AbortCode::None) {
        std::memcpy(data_.data(), body.data() + sdo::kInitiateBody, in_frame);
        transfer_ = Transfer{TransferKind::Download, index, subindex, ca, 0, size, in_frame};
      }
    }
  }
  if (rc != AbortCode::None) {
    return abort(reply, index, subindex, rc);
  }
  // Initiate download response (Table 37): 0x60 (| CA), index, subindex, 4 reserved bytes.
  uint8_t* b = reply.data() + kBodyOffset;
  b[0] = static_cast<uint8_t>((sdo::kScsDownloadInitiate << 5) | (ca ? sdo::kCompleteAccess : 0));
  le::put16(b + 1, index);
  b[3] = subindex;
  le::put32(b + 4, 0);
  return finish_coe(reply, sdo::kInitiateBody, kResponse);
}

size_t SdoServer::download_segment(std::span<const uint8_t> body, std::span<uint8_t> reply,
                                   EsmState state) {
  const uint8_t cmd = body[0];
  const Transfer t = transfer_;
  if (t.kind != TransferKind::Download) {
    return abort(reply, t.index, t.subindex, AbortCode::CommandSpecifier);
  }
  if ((cmd & sdo::kToggle) != t.toggle) {
    return abort(reply, t.index, t.subindex, AbortCode::ToggleBit);
  }
  // Segment data (Table 40): a mailbox longer than the minimum carries body - 1 bytes;
  // the minimum (7 data bytes) says in bits 1-3 how many of them are unused.
  const size_t seg = body.size() > sdo::kSegmentMinBody ? body.size() - 1 : 7 - ((cmd >> 1) & 0x07);
  if (t.done + seg > t.size) {
    return abort(reply, t.index, t.subindex, AbortCode::LengthMismatch);
  }
  std::memcpy(data_.data() + t.done, body.data() + 1, seg);
  transfer_.done += seg;
  const bool last = (cmd & sdo::kLastSegment) != 0;
  if (last) {
    if (transfer_.done != t.size) {
      return abort(reply, t.index, t.subindex, AbortCode::LengthMismatch);
    }
    Object* obj = od_.find(t.index);
    if (!obj) {
      return abort(reply, t.index, t.subindex, AbortCode::ObjectNotFound);
    }
    const AbortCode rc =
        commit_download(*obj, t.subindex, t.complete_access, {data_.data(), t.size}, state);
    if (rc != AbortCode::None) {
      return abort(reply, t.index, t.subindex, rc);
    }
    transfer_ = {};
  } else {
    transfer_.toggle ^= sdo::kToggle;
  }
  // Download segment response (Table 41): 0x20 | toggle, 7 reserved bytes.
  uint8_t* b = reply.data() + kBodyOffset;
  b[0] = static_cast<uint8_t>((sdo::kScsDownloadSegment << 5) | t.toggle);
  std::memset(b + 1, 0, 7);
  return finish_coe(reply, sdo::kSegmentMinBody, kResponse);
}

}  // namespace rackcat::coe
