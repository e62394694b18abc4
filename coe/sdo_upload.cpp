// SDO upload: expedited, normal and segmented, single entry or complete access
// (ETG.1000.6 §5.6.2.4 - §5.6.2.6).
#include <algorithm>
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

size_t SdoServer::upload_initiate(std::span<const uint8_t> body, std::span<uint8_t> reply,
                                  EsmState state) {
  const auto [cmd, index, subindex, ca, obj] = begin_initiate(body);
  if (!obj) {
    return abort(reply, index, subindex, missing_object());
  }

  uint8_t* b = reply.data() + kBodyOffset;
  const uint8_t ca_bit = ca ? sdo::kCompleteAccess : 0;
  size_t n = 0;
  const Entry* entry = nullptr;
  if (!ca) {
    entry = obj->entry(subindex);
    if (!entry || entry->padding) {
      return abort(reply, index, subindex, AbortCode::SubindexNotFound);
    }
    if (AbortCode rc = check_read_access(entry->access, state); rc != AbortCode::None) {
      return abort(reply, index, subindex, rc);
    }
    if (obj->hooks().before_read) {
      obj->hooks().before_read(*obj, subindex);
    }
    n = entry->byte_length();
    if (n >= 1 && n <= 4) {
      // Expedited (Table 38): 0x43 | (4 - n) << 2, data in the 4 bytes after the subindex.
      b[0] = static_cast<uint8_t>((sdo::kScsUploadInitiate << 5) | sdo::kExpedited |
                                  sdo::kSizeIndicated | ((4 - n) << 2));
      le::put16(b + 1, index);
      b[3] = subindex;
      le::put32(b + 4, 0);
      copy_bits(b + 4, 0, obj->image().data(), entry->bit_offset, entry->bit_length);
      return finish_coe(reply, sdo::kInitiateBody, kResponse);
    }
  } else if (AbortCode rc = read_complete(*obj, subindex, state, n); rc != AbortCode::None) {
    return abort(reply, index, subindex, rc);
  }

  // Normal response (Table 39): 0x41 (| CA), complete size, then as much data as fits.
  const size_t room = reply.size() - kBodyOffset - sdo::kInitiateBody;
  const uint8_t* src = nullptr;
  uint8_t* dst = b + sdo::kInitiateBody;
  if (n > room) {
    // Segmented (§5.6.2.6): snapshot the value so every segment belongs to one consistent value.
    if (n > data_.size()) {
      return abort(reply, index, subindex, AbortCode::OutOfMemory);
    }
    dst = data_.data();
  }
  if (ca) {
    ca_extract(*obj, subindex, ca_last_subindex(*obj), dst);
  } else {
    std::memset(dst, 0, n);
    copy_bits(dst, 0, obj->image().data(), entry->bit_offset, entry->bit_length);
  }
  b[0] = static_cast<uint8_t>((sdo::kScsUploadInitiate << 5) | sdo::kSizeIndicated | ca_bit);
  le::put16(b + 1, index);
  b[3] = subindex;
  le::put32(b + 4, static_cast<uint32_t>(n));
  size_t first = n;
  if (n > room) {
    first = room;
    src = data_.data();
    std::memcpy(b + sdo::kInitiateBody, src, first);
    transfer_ = Transfer{TransferKind::Upload, index, subindex, ca, 0, n, first};
  }
  return finish_coe(reply, sdo::kInitiateBody + first, kResponse);
}

size_t SdoServer::upload_segment(std::span<const uint8_t> body, std::span<uint8_t> reply) {
  const uint8_t cmd = body[0];
  if (transfer_.kind != TransferKind::Upload) {
    return abort(reply, transfer_.index, transfer_.subindex, AbortCode::CommandSpecifier);
  }
  if ((cmd & sdo::kToggle) != transfer_.toggle) {
    return abort(reply, transfer_.index, transfer_.subindex, AbortCode::ToggleBit);
  }

  // Upload segment response (Table 42): data fills the mailbox; fewer than 7 bytes are padded
  // to 7 with the count of unused bytes in bits 1-3.
  const size_t room = reply.size() - kBodyOffset - 1;
  const size_t remaining = transfer_.size - transfer_.done;
  const size_t chunk = std::min(remaining, room);
  const bool last = chunk == remaining;
  uint8_t* b = reply.data() + kBodyOffset;
  b[0] = static_cast<uint8_t>((sdo::kScsUploadSegment << 5) | transfer_.toggle |
                              (last ? sdo::kLastSegment : 0) | (chunk < 7 ? (7 - chunk) << 1 : 0));
  std::memcpy(b + 1, data_.data() + transfer_.done, chunk);
  if (chunk < 7) {
    std::memset(b + 1 + chunk, 0, 7 - chunk);
  }
  transfer_.done += chunk;
  transfer_.toggle ^= sdo::kToggle;
  if (last) {
    transfer_ = {};
  }
  return finish_coe(reply, 1 + std::max<size_t>(chunk, 7), kResponse);
}

}  // namespace rackcat::coe
