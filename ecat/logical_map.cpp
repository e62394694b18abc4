#include "ecat/logical_map.hpp"

#include <algorithm>

namespace rackcat::ecat {

LogicalMap::LogicalMap(size_t slaves, size_t fmmus_per_slave) {
  entries_.reserve(slaves * fmmus_per_slave);
  reach_.reserve(slaves * fmmus_per_slave);
  hits_.reserve(slaves * fmmus_per_slave);
  for (Cached& c : cache_) c.targets.reserve(slaves);
}

void LogicalMap::clear() {
  entries_.clear();
  reach_.clear();
  for (Cached& c : cache_) c.valid = false;
}

void LogicalMap::add(uint32_t slave, uint64_t first_bit, uint64_t last_bit, uint8_t fmmu) {
  entries_.push_back(Entry{first_bit, last_bit, slave, fmmu});
}

void LogicalMap::finish() {
  std::sort(entries_.begin(), entries_.end(),
            [](const Entry& a, const Entry& b) { return a.first_bit < b.first_bit; });
  uint64_t reach = 0;
  for (const Entry& e : entries_) {
    reach = std::max(reach, e.last_bit);
    reach_.push_back(reach);
  }
  for (Cached& c : cache_) c.valid = false;
}

const std::vector<LogicalMap::Target>* LogicalMap::resolve(uint32_t address, uint16_t length) {
  for (Cached& c : cache_) {
    if (c.valid && c.address == address && c.length == length) {
      c.used_in_frame = frame_;
      return &c.targets;
    }
  }
  // Replace an empty slot or the range used longest ago, never one handed out in this frame.
  Cached* victim = nullptr;
  for (Cached& c : cache_) {
    if (c.valid && c.used_in_frame == frame_) continue;
    const uint64_t age = c.valid ? c.used_in_frame : 0;
    if (victim == nullptr || age < (victim->valid ? victim->used_in_frame : 0)) victim = &c;
  }
  if (victim == nullptr) return nullptr;
  compute(address, length, victim->targets);
  victim->address = address;
  victim->length = length;
  victim->valid = true;
  victim->used_in_frame = frame_;
  return &victim->targets;
}

void LogicalMap::compute(uint32_t address, uint16_t length, std::vector<Target>& out) {
  out.clear();
  if (length == 0 || entries_.empty()) return;
  const uint64_t lo = static_cast<uint64_t>(address) * 8;
  const uint64_t hi = (static_cast<uint64_t>(address) + length) * 8 - 1;
  // reach_ is non-decreasing: entries before the first whose reach gets to `lo` all end below.
  auto i = static_cast<size_t>(std::lower_bound(reach_.begin(), reach_.end(), lo) - reach_.begin());
  hits_.clear();
  for (; i < entries_.size() && entries_[i].first_bit <= hi; ++i) {
    if (entries_[i].last_bit >= lo) hits_.push_back(entries_[i]);
  }
  // Line order (a master usually lays the slaves out in order: then this is only a check).
  auto by_slave = [](const Entry& a, const Entry& b) { return a.slave < b.slave; };
  if (!std::is_sorted(hits_.begin(), hits_.end(), by_slave)) {
    std::sort(hits_.begin(), hits_.end(), by_slave);
  }
  for (const Entry& e : hits_) {
    const auto bit = static_cast<uint16_t>(1u << e.fmmu);
    if (!out.empty() && out.back().slave == e.slave) {
      out.back().fmmus = static_cast<uint16_t>(out.back().fmmus | bit);
    } else {
      out.push_back(Target{e.slave, bit});
    }
  }
}

}  // namespace rackcat::ecat
