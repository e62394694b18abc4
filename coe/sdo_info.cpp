// SDO Information (ETG.1000.6 §5.6.3): OD lists, object and entry descriptions, fragmented
// over as many mailboxes as needed (the first answers the request, the rest go out through
// poll()), and SDO Information error replies.
#include <algorithm>
#include <cstring>

#include "coe/bits.hpp"
#include "coe/coe_header.hpp"
#include "coe/entry_check.hpp"
#include "coe/sdo_info.hpp"
#include "coe/sdo_server.hpp"

namespace rackcat::coe {
namespace {
constexpr size_t kBodyOffset = CoeHeader::kSize;
constexpr uint8_t kService = static_cast<uint8_t>(CoeService::SdoInformation);

uint16_t object_data_type(const Object& obj) {
  if (obj.data_type() != 0) {
    return obj.data_type();
  }
  // VAR: the value's type; ARRAY: the element type (subindex 1).
  if (obj.code() == ObjectCode::Var) {
    if (const Entry* e = obj.entry(0)) {
      return e->data_type;
    }
  } else if (obj.code() == ObjectCode::Array) {
    if (const Entry* e = obj.entry(1)) {
      return e->data_type;
    }
  } else {
    // A RECORD without a standard structure of its own is the generic RECORD type (0x002A);
    // data type 0 is "unknown" to masters.
    return record_type::kRecord;
  }
  return 0;
}
}  // namespace

bool SdoServer::in_list(const Object& obj, uint16_t list_type) const {
  switch (list_type) {
    case sdo_info::kListAll:
      return true;
    case sdo_info::kListRxPdoMappable:
      return obj.combined_access() & access::kRxPdoMappable;
    case sdo_info::kListTxPdoMappable:
      return obj.combined_access() & access::kTxPdoMappable;
    case sdo_info::kListBackup:
      return obj.combined_access() & access::kBackup;
    case sdo_info::kListSettings:
      return obj.combined_access() & access::kSettings;
    default:
      return false;
  }
}

size_t SdoServer::list_count(uint16_t list_type) const {
  size_t n = 0;
  for (size_t i = 0; i < od_.size(); ++i) {
    n += in_list(od_.at(i), list_type);
  }
  return n;
}

size_t SdoServer::info_error(std::span<uint8_t> reply, AbortCode code) {
  // §5.6.3.8: opcode 7, fragments left 0, the abort code.
  info_ = {};
  uint8_t* b = reply.data() + kBodyOffset;
  b[0] = sdo_info::kErrorRequest;
  b[1] = 0;
  le::put16(b + 2, 0);
  le::put32(b + 4, static_cast<uint32_t>(code));
  return finish_coe(reply, sdo_info::kHeaderSize + 4, kService);
}

size_t SdoServer::describe_object(const Object& obj) {
  // §5.6.3.5.2: index, data type, max subindex, object code, name.
  uint8_t* p = info_buf_.data();
  le::put16(p, obj.index());
  le::put16(p + 2, object_data_type(obj));
  p[4] = obj.max_subindex();
  p[5] = static_cast<uint8_t>(obj.code());
  const size_t name = std::min(obj.name().size(), info_buf_.size() - 6);
  std::copy_n(obj.name().data(), name, p + 6);
  return 6 + name;
}

size_t SdoServer::describe_entry(const Object& obj, const Entry& e, uint8_t value_info) {
  // §5.6.3.6.2: index, subindex, value info, data type, bit length, object access, then the
  // requested values (unit type, default, minimum, maximum) and the name.
  uint8_t* p = info_buf_.data();
  le::put16(p, obj.index());
  p[2] = e.subindex;
  le::put16(p + 4, e.data_type);
  le::put16(p + 6, e.bit_length);
  le::put16(p + 8, e.access);
  size_t pos = 10;
  uint8_t given = 0;
  const size_t len = e.byte_length();
  // Values of an entry larger than the buffer sized by prepare() are left out (bits cleared).
  if (10 + 2 + 3 * len > info_buf_.size()) {
    value_info &= sdo_info::kValueUnitType;
  }
  if (value_info & sdo_info::kValueUnitType) {
    le::put16(p + pos, e.unit_type);
    pos += 2;
    given |= sdo_info::kValueUnitType;
  }
  if (value_info & sdo_info::kValueDefault) {
    std::memset(p + pos, 0, len);
    if (!e.default_value.empty()) {
      std::memcpy(p + pos, e.default_value.data(), std::min(len, e.default_value.size()));
    }
    pos += len;
    given |= sdo_info::kValueDefault;
  }
  // Minimum and maximum exist for integer types only (REAL and strings have none here).
  const bool ranged = is_integer_entry(e) && len <= 8;
  if ((value_info & sdo_info::kValueMinimum) && ranged) {
    le::put(p + pos, len, static_cast<uint64_t>(effective_min(e)));
    pos += len;
    given |= sdo_info::kValueMinimum;
  }
  if ((value_info & sdo_info::kValueMaximum) && ranged) {
    le::put(p + pos, len, static_cast<uint64_t>(effective_max(e)));
    pos += len;
    given |= sdo_info::kValueMaximum;
  }
  p[3] = given;
  const size_t name = std::min(e.name.size(), info_buf_.size() - pos);
  std::copy_n(e.name.data(), name, p + pos);  // no terminator on the wire
  return pos + name;
}

size_t SdoServer::sdo_info(std::span<const uint8_t> body, std::span<uint8_t> reply) {
  const uint8_t opcode = body[0] & 0x7F;
  // Requests are never fragmented (§5.6.3.2): an incomplete flag or fragments left is a
  // malformed SDO Information header.
  if ((body[0] & sdo_info::kIncomplete) || le::get16(&body[2]) != 0) {
    return mailbox_error(mailbox::Error::InvalidHeader);
  }
  const auto data = body.subspan(sdo_info::kHeaderSize);
  // Fragment payloads stay even so list entries never straddle two mailboxes (masters such as
  // SOEM read each fragment as whole 16-bit words).
  const size_t fragment = (reply.size() - kBodyOffset - sdo_info::kHeaderSize) & ~size_t{1};

  switch (opcode) {
    case sdo_info::kGetOdListRequest: {
      if (data.size() < 2) {
        return mailbox_error(mailbox::Error::SizeTooShort);
      }
      const uint16_t list_type = le::get16(data.data());
      if (list_type > sdo_info::kListSettings) {
        return info_error(reply, AbortCode::UnsupportedAccess);
      }
      if (list_type == sdo_info::kListLengths) {
        // §5.6.3.3.2: list type 0 answers with the length of lists 1..5 (fragmented like any
        // other answer when the mailbox is small).
        uint8_t* p = info_buf_.data();
        le::put16(p, list_type);
        for (uint16_t t = 1; t <= 5; ++t) {
          le::put16(p + 2 * t, static_cast<uint16_t>(list_count(t)));
        }
        return start_fragments(reply, InfoKind::Buffer, sdo_info::kGetOdListResponse, 12, fragment);
      }
      return start_fragments(reply, InfoKind::List, sdo_info::kGetOdListResponse,
                             2 + 2 * list_count(list_type), fragment, list_type);
    }
    case sdo_info::kGetObjectDescriptionRequest: {
      if (data.size() < 2) {
        return mailbox_error(mailbox::Error::SizeTooShort);
      }
      const Object* obj = od_.find(le::get16(data.data()));
      if (!obj) {
        return info_error(reply, AbortCode::ObjectNotFound);
      }
      return start_fragments(reply, InfoKind::Buffer, sdo_info::kGetObjectDescriptionResponse,
                             describe_object(*obj), fragment);
    }
    case sdo_info::kGetEntryDescriptionRequest: {
      if (data.size() < 4) {
        return mailbox_error(mailbox::Error::SizeTooShort);
      }
      const Object* obj = od_.find(le::get16(data.data()));
      if (!obj) {
        return info_error(reply, AbortCode::ObjectNotFound);
      }
      // Padding entries inside the object's max subindex are described too (access 0): the
      // object description announces them, and SOEM's ecx_readOE fails the whole object when
      // one subindex up to MaxSub has no description. SDO upload/download of a padding
      // subindex still aborts with 0x06090011.
      const Entry* e = obj->entry(data[2]);
      if (!e && data[2] <= obj->max_subindex()) {
        // A gap below MaxSubindex (0x1C32/0x1C33 subindices 0x0D..0x1F) is described like a
        // padding entry, with no data type, no bits and no access, so a master reading every
        // subindex up to MaxSubindex gets a clean listing.
        static const Entry kGap = [] {
          Entry g;
          g.name = "Reserved";
          g.padding = true;
          return g;
        }();
        Entry gap = kGap;
        gap.subindex = data[2];
        return start_fragments(reply, InfoKind::Buffer, sdo_info::kGetEntryDescriptionResponse,
                               describe_entry(*obj, gap, data[3]), fragment);
      }
      if (!e) {
        return info_error(reply, AbortCode::SubindexNotFound);
      }
      return start_fragments(reply, InfoKind::Buffer, sdo_info::kGetEntryDescriptionResponse,
                             describe_entry(*obj, *e, data[3]), fragment);
    }
    case sdo_info::kErrorRequest:
      // The master aborts a fragmented answer: stop sending, no reply.
      info_ = {};
      return 0;
    default:
      return info_error(reply, AbortCode::CommandSpecifier);
  }
}

size_t SdoServer::start_fragments(std::span<uint8_t> reply, InfoKind kind, uint8_t opcode,
                                  size_t total, size_t fragment, uint16_t list_type) {
  info_ = {};
  info_.kind = kind;
  info_.opcode = opcode;
  info_.list_type = list_type;
  info_.total = total;
  info_.fragment_size = fragment;
  info_.fragments_left = static_cast<uint16_t>((total + fragment - 1) / fragment - 1);
  return info_fragment(reply);
}

size_t SdoServer::info_fragment(std::span<uint8_t> reply) {
  // Fragments keep the size announced by fragments-left; a smaller mailbox waits.
  const size_t room = (reply.size() - kBodyOffset - sdo_info::kHeaderSize) & ~size_t{1};
  if (room < info_.fragment_size && info_.sent != 0) {
    return 0;
  }
  const size_t chunk = std::min(info_.fragment_size, info_.total - info_.sent);
  const bool more = info_.sent + chunk < info_.total;
  uint8_t* b = reply.data() + kBodyOffset;
  b[0] = static_cast<uint8_t>(info_.opcode | (more ? sdo_info::kIncomplete : 0));
  b[1] = 0;
  le::put16(b + 2, more ? info_.fragments_left : 0);
  uint8_t* out = b + sdo_info::kHeaderSize;
  if (info_.kind == InfoKind::Buffer) {
    std::memcpy(out, info_buf_.data() + info_.sent, chunk);
  } else {
    // The list response is the word stream [list type, index, index, ...]; fragments start
    // on even byte offsets, so each writes whole words, resuming the dictionary scan.
    size_t word = info_.sent / 2;
    for (size_t i = 0; i < chunk / 2; ++i, ++word) {
      uint16_t value = info_.list_type;
      if (word != 0) {
        while (info_.cursor < od_.size() && !in_list(od_.at(info_.cursor), info_.list_type)) {
          ++info_.cursor;
        }
        // The dictionary cannot shrink mid-list on the request path; guard anyway.
        value = info_.cursor < od_.size() ? od_.at(info_.cursor++).index() : 0;
      }
      le::put16(out + 2 * i, value);
    }
  }
  info_.sent += chunk;
  if (!more) {
    info_ = {};
  } else {
    --info_.fragments_left;
  }
  return finish_coe(reply, sdo_info::kHeaderSize + chunk, kService);
}

}  // namespace rackcat::coe
