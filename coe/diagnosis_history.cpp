// ETG.1020 ch. 13 diagnosis history: see diagnosis_history.hpp for the object and the rules.
#include "coe/diagnosis_history.hpp"

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "base/little_endian.hpp"

namespace rackcat::coe::diag {

bool Message::add(uint16_t type, uint32_t value, uint8_t size) {
  if (parameter_bytes + 2u + size > kMaxParameterBytes || parameter_count == 0xFF) return false;
  uint8_t* p = parameters.data() + parameter_bytes;
  p[0] = static_cast<uint8_t>(type);
  p[1] = static_cast<uint8_t>(type >> 8);
  for (uint8_t i = 0; i < size; ++i) p[2 + i] = static_cast<uint8_t>(value >> (8 * i));
  parameter_bytes = static_cast<uint8_t>(parameter_bytes + 2 + size);
  ++parameter_count;
  return true;
}

namespace {
// ETG.1000.6 data type index -> size of the parameter value (the integer types a message uses).
size_t parameter_size(uint16_t flag) {
  switch (flag) {
    case 0x0001:  // BOOLEAN
    case 0x0002:  // INTEGER8
    case 0x0005:  // UNSIGNED8
      return 1;
    case 0x0003:  // INTEGER16
    case 0x0006:  // UNSIGNED16
      return 2;
    case 0x0004:  // INTEGER32
    case 0x0007:  // UNSIGNED32
    case 0x0008:  // REAL32
      return 4;
    default:
      // Bits 12..15 = 1/2/3 (byte array, ASCII, Unicode): bits 0..11 are the length.
      return (flag >> 12) >= 1 && (flag >> 12) <= 3 ? (flag & 0x0FFF) : 0;
  }
}
}  // namespace

uint32_t Message::parameter(size_t n) const {
  size_t pos = 0;
  for (size_t i = 0; i < parameter_count && pos + 2 <= parameter_bytes; ++i) {
    const auto flag = le::get16(&parameters[pos]);
    const size_t size = parameter_size(flag);
    if (size == 0 || pos + 2 + size > parameter_bytes) return 0;
    if (i == n) {
      if (size > 4) return 0;
      uint32_t v = 0;
      for (size_t b = 0; b < size; ++b)
        v |= static_cast<uint32_t>(parameters[pos + 2 + b]) << (8 * b);
      return v;
    }
    pos += 2 + size;
  }
  return 0;
}

std::optional<Message> decode(std::span<const uint8_t> slot) {
  if (slot.size() < 16 || std::all_of(slot.begin(), slot.end(), [](uint8_t b) { return b == 0; }))
    return std::nullopt;
  auto get = [&](size_t at, size_t n) {
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) v |= static_cast<uint64_t>(slot[at + i]) << (8 * i);
    return v;
  };
  Message m;
  m.diag_code = static_cast<uint32_t>(get(0, 4));
  const auto flags = static_cast<uint16_t>(get(4, 2));
  m.type = static_cast<Type>(flags & 0x0F);
  m.local_time = (flags & kMessageLocalTime) != 0;
  m.text_id = static_cast<uint16_t>(get(6, 2));
  m.time_ns = get(8, 8);
  // Copy whole parameters while they fit.
  const size_t avail = std::min(slot.size() - 16, kMaxParameterBytes);
  size_t pos = 0;
  uint8_t count = 0;
  for (unsigned i = 0; i < (flags >> 8); ++i) {
    if (pos + 2 > avail) break;
    const auto flag = le::get16(&slot[16 + pos]);
    const size_t size = parameter_size(flag);
    if (size == 0 || pos + 2 + size > avail) break;
    pos += 2 + size;
    ++count;
  }
  std::copy_n(slot.begin() + 16, pos, m.parameters.begin());
  m.parameter_bytes = static_cast<uint8_t>(pos);
  m.parameter_count = count;
  return m;
}

std::array<uint8_t, kMessageBytes> encode(const Message& m) {
  std::array<uint8_t, kMessageBytes> out{};
  auto put = [&out](size_t at, uint64_t v, size_t n) {
    for (size_t i = 0; i < n; ++i) out[at + i] = static_cast<uint8_t>(v >> (8 * i));
  };
  const uint16_t flags = static_cast<uint16_t>((static_cast<uint16_t>(m.type) & 0x0F) |
                                               (m.local_time ? kMessageLocalTime : 0) |
                                               (static_cast<uint16_t>(m.parameter_count) << 8));
  put(0, m.diag_code, 4);
  put(4, flags, 2);
  put(6, m.text_id, 2);
  put(8, m.time_ns, 8);
  std::copy_n(m.parameters.begin(), m.parameter_bytes, out.begin() + 16);
  return out;
}

History::History(uint8_t capacity) : capacity_(capacity) {
  if (capacity == 0 || capacity > 250) {
    throw std::invalid_argument("diagnosis history capacity must be 1..250");
  }
}

Object History::make_object(uint16_t default_flags) const {
  auto u8 = [](uint8_t v) { return std::vector<uint8_t>{v}; };
  Object o(kIndex, ObjectCode::Record, "Diagnosis History");
  o.add(make_entry(0, "SubIndex 000", DataType::Unsigned8, 8, access::kRo,
                   u8(static_cast<uint8_t>(kFirstMessage - 1 + capacity_))));
  o.add(make_entry(1, "Maximum Messages", DataType::Unsigned8, 8, access::kRo, u8(capacity_)));
  o.add(make_entry(2, "Newest Message", DataType::Unsigned8, 8, access::kRo, u8(0)));
  o.add(make_entry(3, "Newest Acknowledged Message", DataType::Unsigned8, 8, access::kRw, u8(0)));
  o.add(make_entry(4, "New Messages Available", DataType::Boolean, 1,
                   access::kRo | access::kTxPdoMappable, u8(0)));
  o.add(
      make_entry(5, "Flags", DataType::Unsigned16, 16, access::kRw,
                 {static_cast<uint8_t>(default_flags), static_cast<uint8_t>(default_flags >> 8)}));
  for (uint8_t i = 0; i < capacity_; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "Diagnosis Message %03u", static_cast<unsigned>(i + 1));
    o.add(make_entry(static_cast<uint8_t>(kFirstMessage + i), name, DataType::OctetString,
                     kMessageBytes * 8, access::kRo, std::vector<uint8_t>(kMessageBytes, 0)));
  }
  o.finalize();
  return o;
}

void History::bind(Object& object) {
  object_ = &object;
  flags_ = static_cast<uint16_t>(object.get_u(5) & kFlagsWritable);
  object.edit_hooks().before_read = [this](Object&, int subindex) { on_read(subindex); };
  object.edit_hooks().validate_write = [this](const Object& obj, int subindex,
                                              std::span<const uint8_t> data,
                                              EsmState) -> AbortCode {
    auto at = [&](uint8_t sub) -> std::span<const uint8_t> {
      if (subindex != -1) return data;
      const Entry* e = obj.entry(sub);
      return data.subspan(e->bit_offset / 8, e->byte_length());
    };
    if (subindex == 5 || subindex == -1) {
      const auto b = at(5);
      const uint16_t v = le::get16(&b[0]);
      // Bit 5 is read only: a write-back of what was read is not an error.
      if (v & ~(kFlagsWritable | kFlagOverflow)) return AbortCode::ValueRange;
    }
    if (subindex == 3 || subindex == -1) {
      const uint8_t v = at(3)[0];
      if (subindex == 3 || v != obj.get_u(3)) {
        if (AbortCode rc = check_newest_acknowledged(v); rc != AbortCode::None) return rc;
      }
    }
    return AbortCode::None;
  };
  object.edit_hooks().after_write = [this](Object& obj, int subindex) {
    // The committed bytes are the request; execute it, then publish the real state.
    const auto ack = static_cast<uint8_t>(obj.get_u(3));
    const auto fl = static_cast<uint16_t>(obj.get_u(5));
    const uint8_t old_ack = acked_ ? subindex_of(acked_ - 1) : 0;
    if (subindex == 5 || subindex == -1) write_flags(static_cast<uint16_t>(fl & kFlagsWritable));
    if (subindex == 3 || (subindex == -1 && ack != old_ack)) write_newest_acknowledged(ack);
    publish();
  };
  head_ = count_ = acked_ = 0;
  unread_ = overflow_ = false;
  for (size_t r = 0; r < capacity_; ++r) clear_slot(r);
  publish();
}

uint16_t History::flags() const {
  return static_cast<uint16_t>(flags_ | (overflow_ ? kFlagOverflow : 0));
}

bool History::new_messages() const {
  return acknowledge_mode() ? count_ > acked_ : unread_;
}

uint8_t History::subindex_of(size_t age) const {
  if (age >= count_) return 0;
  return static_cast<uint8_t>(kFirstMessage + (oldest_ring() + age) % capacity_);
}

std::span<const uint8_t> History::slot(uint8_t subindex) const {
  if (!object_) return {};
  return static_cast<const Object*>(object_)->bytes(subindex);
}

void History::clear_slot(size_t ring) {
  if (!object_) return;
  auto b = object_->bytes(static_cast<uint8_t>(kFirstMessage + ring));
  std::fill(b.begin(), b.end(), 0);
}

void History::drop_oldest() {
  clear_slot(oldest_ring());
  --count_;
  if (acked_) --acked_;
}

AddResult History::add(const Message& m) {
  const uint16_t disabled = m.type == Type::Info      ? kFlagDisableInfo
                            : m.type == Type::Warning ? kFlagDisableWarning
                                                      : kFlagDisableError;
  if (flags_ & disabled) return AddResult::Filtered;
  if (count_ == capacity_) {
    if (acknowledge_mode()) {
      if (acked_ == 0) {
        overflow_ = true;
        publish();
        return AddResult::Discarded;
      }
      drop_oldest();
    } else {
      if (acked_ == 0) overflow_ = true;  // an unacknowledged message is lost
      drop_oldest();
    }
  }
  const auto bytes = encode(m);
  if (object_) {
    auto dst = object_->bytes(static_cast<uint8_t>(kFirstMessage + head_));
    std::copy(bytes.begin(), bytes.end(), dst.begin());
  }
  head_ = (head_ + 1) % capacity_;
  ++count_;
  unread_ = true;
  publish();
  return AddResult::Stored;
}

void History::clear() {
  for (size_t r = 0; r < capacity_; ++r) clear_slot(r);
  head_ = count_ = acked_ = 0;
  unread_ = overflow_ = false;
  publish();
}

AbortCode History::check_newest_acknowledged(uint8_t subindex) const {
  if (subindex == 0) return AbortCode::None;
  if (subindex < kFirstMessage) return AbortCode::ValueTooLow;
  if (subindex >= kFirstMessage + capacity_) return AbortCode::ValueTooHigh;
  const size_t age = (ring_of_subindex(subindex) + capacity_ - oldest_ring()) % capacity_;
  if (age >= count_) return AbortCode::ValueRange;
  return AbortCode::None;
}

AbortCode History::write_newest_acknowledged(uint8_t subindex) {
  if (AbortCode rc = check_newest_acknowledged(subindex); rc != AbortCode::None) return rc;
  if (subindex == 0) {
    if (acknowledge_mode()) {
      while (acked_) drop_oldest();  // the acknowledged messages are deleted
    } else {
      while (count_) drop_oldest();  // every message is deleted
      head_ = 0;
      unread_ = false;
    }
    overflow_ = false;
  } else {
    const size_t age = (ring_of_subindex(subindex) + capacity_ - oldest_ring()) % capacity_;
    acked_ = age + 1;
    if (acked_ == count_) unread_ = false;
  }
  publish();
  return AbortCode::None;
}

AbortCode History::write_flags(uint16_t value) {
  if (value & ~(kFlagsWritable | kFlagOverflow)) return AbortCode::ValueRange;
  flags_ = static_cast<uint16_t>(value & kFlagsWritable);
  publish();
  return AbortCode::None;
}

void History::on_read(int subindex) {
  // Only an SDO read of the newest message's own subindex counts: the process image calls
  // the hook with -1 every cycle to pack a mapped 0x10F3:04, and a complete access reads
  // the control entries along with the messages.
  if (!acknowledge_mode() && count_ && subindex == static_cast<int>(newest_subindex())) {
    unread_ = false;
    publish();
  }
}

void History::publish() {
  if (!object_) return;
  object_->set_u(2, newest_subindex());
  object_->set_u(3, acked_ ? subindex_of(acked_ - 1) : 0);
  object_->set_u(4, new_messages() ? 1 : 0);
  object_->set_u(5, flags());
}

}  // namespace rackcat::coe::diag
