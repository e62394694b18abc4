// The logical address space of a line (ETG.1000.4 §6.6): which slaves' FMMUs a logical
// datagram (LRD, LWR, LRW) meets, so that Segment hands the datagram only to those ESCs instead
// of letting every ESC of the line intersect it with each of its FMMUs.
//
// Built from every ESC's activated FMMUs (Esc::fmmu_ranges) and rebuilt whenever one of them
// may have changed (Esc::set_fmmu_generation: a write to 0x0600-0x06FF, an ESC reset). A
// datagram's targets are the slaves, in line order, with the FMMUs whose logical bit range
// meets the datagram's; each ESC still intersects those FMMUs itself (bit edges, the 64 KiB
// physical end, read/write type against the command) and counts its working counter once per
// datagram (ETG.1000.4 §5.4.4), so the map only decides who is asked, never what is done.
//
// Cyclic frames repeat their logical datagrams: the targets of the last few (address, length)
// pairs are kept until the map changes. Everything is reserved at construction: resolving and
// rebuilding allocate nothing.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace rackcat::ecat {

class LogicalMap {
 public:
  // One slave a datagram reaches and the FMMUs of it inside the datagram's range.
  struct Target {
    uint32_t slave = 0;
    uint16_t fmmus = 0;  // bit n: FMMU n
  };
  // How many distinct logical datagrams one frame may resolve through the map; a frame with
  // more leaves the rest to each ESC's own FMMU walk (Segment).
  static constexpr size_t kCachedRanges = 8;

  // `slaves` ESCs with at most `fmmus_per_slave` FMMUs each.
  LogicalMap(size_t slaves, size_t fmmus_per_slave);

  // Rebuilding: clear(), add() every activated FMMU of every slave, finish().
  void clear();
  void add(uint32_t slave, uint64_t first_bit, uint64_t last_bit, uint8_t fmmu);
  void finish();

  // Starts a frame: the targets resolve() returns stay valid until the next begin_frame() (at
  // most kCachedRanges datagrams per frame).
  void begin_frame() { ++frame_; }
  // Slaves in line order whose FMMUs meet logical bytes [address, address + length); empty when
  // none does. nullptr when this frame already resolved kCachedRanges other ranges.
  const std::vector<Target>* resolve(uint32_t address, uint16_t length);

  size_t entries() const { return entries_.size(); }

 private:
  struct Entry {
    uint64_t first_bit = 0;
    uint64_t last_bit = 0;
    uint32_t slave = 0;
    uint8_t fmmu = 0;
  };
  struct Cached {
    uint32_t address = 0;
    uint16_t length = 0;
    bool valid = false;
    uint64_t used_in_frame = 0;
    std::vector<Target> targets;
  };
  void compute(uint32_t address, uint16_t length, std::vector<Target>& out);

  std::vector<Entry> entries_;   // sorted by first_bit after finish()
  std::vector<uint64_t> reach_;  // reach_[i] = max last_bit of entries_[0..i]
  std::vector<Entry> hits_;      // scratch of compute()
  std::array<Cached, kCachedRanges> cache_;
  uint64_t frame_ = 1;
};

}  // namespace rackcat::ecat
