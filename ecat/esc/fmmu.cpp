// FMMUs: bit-granular mapping of the 4 GiB logical address space onto this ESC's physical
// memory (ETG.1000.4 §6.6), and the logical datagrams LRD, LWR, LRW that use them.
#include <algorithm>
#include <array>
#include <bit>
#include <cstring>

#include "base/little_endian.hpp"
#include "base/short_copy.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/frame.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

// Mask of the bits of logical byte `byte` that lie inside the bit range [lo, hi].
inline uint8_t byte_mask(uint64_t byte, uint64_t lo, uint64_t hi) {
  uint8_t mask = 0xFF;
  if (byte == lo / 8) mask = static_cast<uint8_t>(mask & (0xFF << (lo % 8)));
  if (byte == hi / 8) mask = static_cast<uint8_t>(mask & (0xFF >> (7 - hi % 8)));
  return mask;
}

// Byte-aligned mapping (the physical bit of a logical bit has the same position in its byte):
// moves logical bits lo..hi from `from` to `to`, both pointing at the byte that holds bit
// `lo`. The partial first and last bytes are merged under their masks (ETG.1000.4 §6.6: bits
// outside the mapping stay as they are), the whole bytes between are copied.
inline void merge_bits(uint8_t* to, const uint8_t* from, uint64_t lo, uint64_t hi) {
  const uint64_t bytes = hi / 8 - lo / 8 + 1;
  if (lo % 8 == 0 && hi % 8 == 7) {  // whole bytes: the usual process-data mapping
    base::copy_bytes(to, from, bytes);
    return;
  }
  const auto first = static_cast<uint8_t>(0xFF << (lo % 8));
  const auto last = static_cast<uint8_t>(0xFF >> (7 - hi % 8));
  auto merge = [&](uint64_t i, uint8_t mask) {
    to[i] = static_cast<uint8_t>((to[i] & ~mask) | (from[i] & mask));
  };
  if (bytes == 1) {
    merge(0, static_cast<uint8_t>(first & last));
    return;
  }
  merge(0, first);
  base::copy_bytes(to + 1, from + 1, bytes - 2);
  merge(bytes - 1, last);
}

}  // namespace

bool Esc::intersect_fmmu(const FmmuState& f, uint64_t dg_lo, uint64_t dg_hi, FmmuSpan& out) {
  if (!f.maps) return false;
  out.lo = std::max(f.first_bit, dg_lo);
  out.hi = std::min(f.last_bit, dg_hi);
  if (out.lo > out.hi) return false;
  out.shift = f.shift;
  const uint64_t p_lo = static_cast<uint64_t>(static_cast<int64_t>(out.lo) + out.shift);
  const uint64_t p_hi = static_cast<uint64_t>(static_cast<int64_t>(out.hi) + out.shift);
  if (p_hi / 8 >= reg::kAddressSpace) return false;
  out.phys_first = static_cast<uint32_t>(p_lo / 8);
  out.phys_len = static_cast<uint32_t>(p_hi / 8 - p_lo / 8 + 1);
  return true;
}

void Esc::reload_fmmu(int index) {
  const uint8_t* p = &mem_[reg::kFmmu + reg::kFmmuSize * index];
  FmmuState& f = fmmu_[index];
  f.logical_start = le::get32(p);
  f.length = le::get16(p + 4);
  f.logical_start_bit = p[6] & 0x07;
  f.logical_stop_bit = p[7] & 0x07;
  f.physical_start = le::get16(p + 8);
  f.physical_start_bit = p[10] & 0x07;
  f.type = p[11] & 0x03;
  // ETG.1000.4 §6.6: logical bits start x 8 + start bit .. (start + length - 1) x 8 + stop
  // bit; a one-byte FMMU whose stop bit lies before its start bit maps nothing.
  f.first_bit = static_cast<uint64_t>(f.logical_start) * 8 + f.logical_start_bit;
  f.last_bit = (static_cast<uint64_t>(f.logical_start) + f.length - 1) * 8 + f.logical_stop_bit;
  f.maps = f.length != 0 && f.last_bit >= f.first_bit;
  f.shift =
      static_cast<int64_t>(static_cast<uint64_t>(f.physical_start) * 8 + f.physical_start_bit) -
      static_cast<int64_t>(f.first_bit);
  fmmu_active_mask_ = 0;
  for (int n = 0; n < kFmmus; ++n) {
    const uint8_t* q = &mem_[reg::kFmmu + reg::kFmmuSize * n];
    if ((q[12] & 0x01) && (q[11] & 0x03)) fmmu_active_mask_ |= static_cast<uint16_t>(1u << n);
  }
  refresh_fmmu_meetings();
  if (fmmu_generation_ != nullptr) ++*fmmu_generation_;  // the segment's map is stale
}

void Esc::refresh_fmmu_meetings() {
  fmmu_meeting_known_ = 0;
  fmmu_whole_mask_ = 0;
  forget_whole_plans();
  for (int n = 0; n < kFmmus; ++n) {
    const FmmuState& f = fmmu_[n];
    if (!f.maps) continue;
    const int64_t p_lo = static_cast<int64_t>(f.first_bit) + f.shift;
    const int64_t p_hi = static_cast<int64_t>(f.last_bit) + f.shift;
    if (p_hi / 8 >= static_cast<int64_t>(reg::kAddressSpace)) continue;
    const auto first = static_cast<uint32_t>(p_lo / 8);
    const auto end = static_cast<uint32_t>(p_hi / 8 + 1);
    const uint16_t meeting = sm_meeting(first, end);
    bool known = meeting == 0;
    if (std::has_single_bit(meeting) && (meeting & sm_alone_mask_) != 0) {
      // Every part of the range meets this SM and, as no other SM shares its bytes, only it.
      const SmState& s = sm_[std::countr_zero(meeting)];
      known = s.start <= first && end <= static_cast<uint32_t>(s.start) + s.length;
    }
    if (!known) continue;
    fmmu_meeting_[n] = meeting;
    fmmu_meeting_known_ = static_cast<uint16_t>(fmmu_meeting_known_ | (1u << n));
    const bool whole_bytes = f.logical_start_bit == 0 && f.logical_stop_bit == 7 &&
                             f.physical_start_bit == 0 && first >= reg::kProcessRam;
    const bool exact = meeting == 0 || (sm_[std::countr_zero(meeting)].start == first &&
                                        sm_[std::countr_zero(meeting)].length == end - first);
    if (whole_bytes && exact)
      fmmu_whole_mask_ = static_cast<uint16_t>(fmmu_whole_mask_ | (1u << n));
  }
}

size_t Esc::fmmu_ranges(std::span<FmmuRange, kFmmus> out) const {
  size_t n = 0;
  for (uint16_t m = fmmu_active_mask_; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    const int i = std::countr_zero(m);
    const FmmuState& f = fmmu_[i];
    if (!f.maps) continue;  // e.g. one byte whose stop bit lies before its start bit
    out[n++] = FmmuRange{f.first_bit, f.last_bit, static_cast<uint8_t>(i)};
  }
  return n;
}

void Esc::logical_datagram(uint8_t* datagram, uint16_t data_len, uint16_t fmmus) {
  uint8_t* data = datagram + kDatagramHeaderSize;
  const uint8_t wkc = process_logical(datagram[0], le::get32(datagram + 2), data, data_len,
                                      static_cast<uint16_t>(fmmus & fmmu_active_mask_));
  leave_datagram(datagram, data_len, wkc);
}

uint8_t Esc::process_logical(uint8_t command, uint32_t address, uint8_t* data, uint16_t len,
                             uint16_t fmmus) {
  if (fmmus == 0 || len == 0) return 0;
  const auto cmd = static_cast<Command>(command);
  // The FMMU types (bit 0 read, bit 1 write) the command uses.
  const uint8_t usable = cmd == Command::Lrw   ? 0x03
                         : cmd == Command::Lrd ? 0x01
                         : cmd == Command::Lwr ? 0x02
                                               : 0x00;
  if ((fmmus & fmmu_whole_mask_) != 0) {
    const int wkc = process_whole_fmmus(cmd, usable, address, data, len, fmmus);
    if (wkc >= 0) return static_cast<uint8_t>(wkc);
  }
  return walk_fmmus(cmd, usable, address, data, len, fmmus);
}

uint8_t Esc::walk_fmmus(Command cmd, uint8_t usable, uint32_t address, uint8_t* data, uint16_t len,
                        uint16_t fmmus) {
  const uint64_t dg_lo = static_cast<uint64_t>(address) * 8;
  const uint64_t dg_hi = (static_cast<uint64_t>(address) + len) * 8 - 1;

  // Each FMMU the command may use is intersected with the datagram once (spans[n] for FMMU
  // n) and counted in the side(s) it serves.
  std::array<FmmuSpan, kFmmus> spans;  // NOLINT: filled for the FMMUs in reads | writes
  FmmuSide reads;
  FmmuSide writes;
  for (uint16_t m = fmmus; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    const int index = std::countr_zero(m);
    const FmmuState& f = fmmu_[index];
    const uint8_t use = f.type & usable;
    if (use == 0) continue;
    FmmuSpan& s = spans[static_cast<size_t>(index)];
    if (!intersect_fmmu(f, dg_lo, dg_hi, s)) continue;
    s.fmmu = index;
    const auto first = static_cast<uint32_t>(s.lo / 8 - address);
    const auto end = static_cast<uint32_t>(s.hi / 8 - address + 1);
    if ((use & 0x01) != 0) reads.add(index, first, end);
    if ((use & 0x02) != 0) writes.add(index, first, end);
  }
  if ((reads.fmmus | writes.fmmus) == 0) return 0;
  const uint8_t* incoming =
      reads.meets(writes) ? keep_incoming(data, writes.first, writes.end) : data;

  bool read_done = false;
  bool write_done = false;
  for (uint16_t m = reads.fmmus; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    read_done |= fmmu_read(spans[static_cast<size_t>(std::countr_zero(m))], dg_lo, data);
  }
  for (uint16_t m = writes.fmmus; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    write_done |= fmmu_write(spans[static_cast<size_t>(std::countr_zero(m))], dg_lo, incoming);
  }
  // ETG.1000.4 §5.4.4: LRD and LWR count 1 per slave; LRW counts 1 for a read, 2 for a write.
  if (cmd == Command::Lrw) return static_cast<uint8_t>((read_done ? 1 : 0) + (write_done ? 2 : 0));
  return (read_done || write_done) ? 1 : 0;
}

const uint8_t* Esc::keep_incoming(const uint8_t* data, uint32_t first, uint32_t end) {
  uint8_t* const incoming = datagram_scratch();
  std::memcpy(incoming + first, data + first, end - first);
  return incoming;
}

void Esc::plan_whole_fmmus(WholePlan& p, uint8_t usable, uint32_t address, uint16_t len,
                           uint16_t fmmus) {
  p = WholePlan{address, len, fmmus, usable, true};
  const uint64_t dg_end = static_cast<uint64_t>(address) + len;
  FmmuSide reads;
  FmmuSide writes;
  for (uint16_t m = fmmus; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    const int index = std::countr_zero(m);
    const FmmuState& f = fmmu_[index];
    const uint8_t use = f.type & usable;
    if (use == 0) continue;
    const uint64_t lo = f.logical_start;
    const uint64_t end = lo + f.length;
    if (end <= address || lo >= dg_end) continue;  // does not meet the datagram
    if ((fmmu_whole_mask_ & (1u << index)) == 0 || lo < address || end > dg_end) return;
    const auto first = static_cast<uint32_t>(lo - address);
    const auto last_end = static_cast<uint32_t>(end - address);
    if ((use & 0x01) != 0) reads.add(index, first, last_end);
    if ((use & 0x02) != 0) writes.add(index, first, last_end);
    p.offset[static_cast<size_t>(index)] = static_cast<uint16_t>(first);
  }
  p.whole = true;
  p.reads = reads.fmmus;
  p.writes = writes.fmmus;
  if (reads.meets(writes)) {
    p.incoming_first = static_cast<uint16_t>(writes.first);
    p.incoming_end = static_cast<uint16_t>(writes.end);
    return;
  }
  plan_exchange(p, usable);
}

void Esc::plan_exchange(WholePlan& p, uint8_t usable) {
  if (usable != 0x03 || !std::has_single_bit(p.reads) || !std::has_single_bit(p.writes)) return;
  const int r = std::countr_zero(p.reads);
  const int w = std::countr_zero(p.writes);
  const uint16_t input = fmmu_meeting_[static_cast<size_t>(r)];
  const uint16_t output = fmmu_meeting_[static_cast<size_t>(w)];
  if (!std::has_single_bit(input) || !std::has_single_bit(output)) return;  // plain memory
  const SmState& in = sm_[std::countr_zero(input)];
  const SmState& out = sm_[std::countr_zero(output)];
  if (!in.active || !out.active || reg::sm::is_mailbox(in.control) ||
      reg::sm::is_mailbox(out.control) || reg::sm::ecat_writes(in.control) ||
      !reg::sm::ecat_writes(out.control)) {
    return;
  }
  p.exchange = true;
  p.exchange_watchdog = (out.control & reg::sm::kControlWatchdog) != 0;
  p.input_sm = static_cast<uint8_t>(std::countr_zero(input));
  p.output_sm = static_cast<uint8_t>(std::countr_zero(output));
  p.input_offset = p.offset[static_cast<size_t>(r)];
  p.output_offset = p.offset[static_cast<size_t>(w)];
}

int Esc::process_whole_fmmus(Command cmd, uint8_t usable, uint32_t address, uint8_t* data,
                             uint16_t len, uint16_t fmmus) {
  const auto planned = [&](const WholePlan& p) {
    return p.valid && p.address == address && p.len == len && p.fmmus == fmmus &&
           p.usable == usable;
  };
  if (!planned(whole_plans_[last_plan_])) {
    last_plan_ ^= 1;  // the other plan, or a new one in its place
    if (!planned(whole_plans_[last_plan_])) {
      plan_whole_fmmus(whole_plans_[last_plan_], usable, address, len, fmmus);
    }
  }
  const WholePlan& p = whole_plans_[last_plan_];
  if (!p.whole) return -1;
  if (p.exchange) return exchange_whole(data);
  if ((p.reads | p.writes) == 0) return 0;
  const uint8_t* incoming = p.incoming_first < p.incoming_end
                                ? keep_incoming(data, p.incoming_first, p.incoming_end)
                                : data;
  bool read_done = false;
  bool write_done = false;
  for (uint16_t m = p.reads; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    const int index = std::countr_zero(m);
    read_done |= whole_fmmu_read(index, data + p.offset[static_cast<size_t>(index)]);
  }
  for (uint16_t m = p.writes; m != 0; m = static_cast<uint16_t>(m & (m - 1))) {
    const int index = std::countr_zero(m);
    write_done |= whole_fmmu_write(index, incoming + p.offset[static_cast<size_t>(index)]);
  }
  if (cmd == Command::Lrw) return (read_done ? 1 : 0) + (write_done ? 2 : 0);
  return (read_done || write_done) ? 1 : 0;
}

int Esc::exchange_whole(uint8_t* data) {
  const WholePlan& p = whole_plans_[last_plan_];
  const bool write = !write_protection_active() || write_allowed(reg::kProcessRam);  // ESC-wide
  return sm_exchange_buffers(p.input_sm, data + p.input_offset, p.output_sm, data + p.output_offset,
                             write, p.exchange_watchdog);
}

bool Esc::whole_fmmu_read(int index, uint8_t* dst) {
  const uint16_t meeting = fmmu_meeting_[index];
  if (meeting != 0) return sm_read_buffer<true>(std::countr_zero(meeting), dst);
  const FmmuState& f = fmmu_[index];
  base::copy_bytes(dst, &mem_[f.physical_start], f.length);
  return true;
}

bool Esc::whole_fmmu_write(int index, const uint8_t* src) {
  if (write_protection_active() && !write_allowed(reg::kProcessRam)) return false;  // ESC-wide
  const uint16_t meeting = fmmu_meeting_[index];
  if (meeting != 0) return sm_write_buffer<true>(std::countr_zero(meeting), src);
  const FmmuState& f = fmmu_[index];
  base::copy_bytes(&mem_[f.physical_start], src, f.length);
  return true;
}

bool Esc::fmmu_read(const FmmuSpan& s, uint64_t dg_lo, uint8_t* data) {
  const uint64_t lo = s.lo;
  const uint64_t hi = s.hi;
  const auto first = static_cast<uint16_t>(s.phys_first);
  const auto plen = static_cast<uint16_t>(s.phys_len);
  const uint16_t meeting = span_meeting(s);
  if (!sm_allows_read(meeting)) return false;
  const bool registers = first < reg::kProcessRam;
  const uint16_t reg_len =
      registers ? static_cast<uint16_t>(
                      std::min<uint32_t>(s.phys_first + s.phys_len, reg::kProcessRam) - first)
                : 0;
  if (registers) before_register_read(first, reg_len);
  if (s.shift % 8 == 0) {
    // Physical and logical bit positions agree: copy whole bytes, masking the edges.
    merge_bits(&data[lo / 8 - dg_lo / 8], &mem_[s.phys_first], lo, hi);
  } else {
    for (uint64_t bit = lo; bit <= hi; ++bit) {
      const uint64_t pb = static_cast<uint64_t>(static_cast<int64_t>(bit) + s.shift);
      const uint64_t db = bit - dg_lo;
      const uint8_t v = (mem_[pb / 8] >> (pb % 8)) & 1;
      data[db / 8] = static_cast<uint8_t>((data[db / 8] & ~(1u << (db % 8))) | (v << (db % 8)));
    }
  }
  sm_after_read(meeting, first, plen);
  if (registers) after_register_read(first, reg_len);
  return true;
}

bool Esc::fmmu_write(const FmmuSpan& s, uint64_t dg_lo, const uint8_t* data) {
  const uint64_t lo = s.lo;
  const uint64_t hi = s.hi;
  const auto first = static_cast<uint16_t>(s.phys_first);
  const auto plen = static_cast<uint16_t>(s.phys_len);
  const uint16_t meeting = span_meeting(s);
  if (!sm_allows_write(meeting)) return false;
  if (write_protection_active() && !write_allowed(reg::kProcessRam)) return false;  // ESC-wide
  if (s.shift % 8 == 0 && s.phys_first >= reg::kProcessRam) {
    // Process RAM, byte-aligned (the usual process-data mapping): no register rules apply.
    merge_bits(&mem_[s.phys_first], &data[lo / 8 - dg_lo / 8], lo, hi);
    sm_after_write(meeting, first, plen);
    return true;
  }
  // Registers keep their write masks and side effects: merge into a copy of the current
  // bytes, then write that copy through the register path in chunks.
  std::array<uint8_t, 256> chunk{};
  uint32_t p = s.phys_first;
  const uint32_t p_end = s.phys_first + s.phys_len;
  while (p < p_end) {
    const bool registers = p < reg::kProcessRam;
    const uint32_t n =
        registers ? std::min<uint32_t>({p_end, reg::kProcessRam, p + 256}) - p : p_end - p;
    uint8_t* target = registers ? chunk.data() : &mem_[p];
    if (registers) std::memcpy(chunk.data(), &mem_[p], n);
    if (s.shift % 8 == 0) {
      for (uint32_t i = 0; i < n; ++i) {
        const int64_t lb = static_cast<int64_t>(p + i) - s.shift / 8;  // logical byte
        const uint8_t mask = byte_mask(static_cast<uint64_t>(lb), lo, hi);
        const uint8_t d = data[static_cast<uint64_t>(lb) - dg_lo / 8];
        target[i] = static_cast<uint8_t>((target[i] & ~mask) | (d & mask));
      }
    } else {
      for (uint64_t bit = lo; bit <= hi; ++bit) {
        const uint64_t pb = static_cast<uint64_t>(static_cast<int64_t>(bit) + s.shift);
        if (pb / 8 < p || pb / 8 >= p + n) continue;
        const uint64_t db = bit - dg_lo;
        const uint8_t v = (data[db / 8] >> (db % 8)) & 1;
        uint8_t& t = target[pb / 8 - p];
        t = static_cast<uint8_t>((t & ~(1u << (pb % 8))) | (v << (pb % 8)));
      }
    }
    if (registers && write_protection_active()) {
      // Register write protection: only the enable registers themselves get through.
      for (uint32_t i = 0; i < n; ++i) {
        if (!write_allowed(p + i)) chunk[i] = mem_[p + i];
      }
    }
    if (registers) {
      write_registers(static_cast<uint16_t>(p), chunk.data(), static_cast<uint16_t>(n));
      after_register_write(static_cast<uint16_t>(p), chunk.data(), static_cast<uint16_t>(n));
    }
    p += n;
  }
  // The register path may have (re)configured a SyncManager: look them up again.
  sm_after_write(sm_meeting(first, s.phys_first + s.phys_len), first, plen);
  return true;
}

}  // namespace rackcat::ecat
