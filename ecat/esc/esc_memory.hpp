// The ESC's 64 KiB address space (registers 0x0000-0x0FFF, process RAM 0x1000-0xFFFF), held
// only as far as the slave uses it. The whole range is reserved as one anonymous mapping, and
// the kernel backs a page of it when the master or the firmware first writes there: a tiny
// rack's ESC keeps its register page and the page with its mailbox and process-data
// SyncManagers resident (8 KiB), not 64 KiB. Reads of RAM nobody wrote return 0, the content
// this ESC model has always given its process RAM at power-on (docs/ESC.md, 0x1000-0xFFFF
// "plain memory"); written bytes read back as written.
//
// Element access is a plain pointer: no check, no fault handling on the datagram path; the
// page faults of a first write are the kernel's (once per page, not per frame).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace rackcat::ecat {

class EscMemory {
 public:
  static constexpr size_t kSize = 0x10000;
  static constexpr size_t kRegisterBytes = 0x1000;  // 0x0000-0x0FFF

  // Reserves the address space (all zero); throws std::bad_alloc when the kernel refuses.
  EscMemory();
  ~EscMemory();
  EscMemory(const EscMemory&) = delete;
  EscMemory& operator=(const EscMemory&) = delete;

  // Power-on content again: registers zeroed, process RAM pages handed back to the kernel, so
  // they read 0 and hold no memory until written.
  void reset();

  uint8_t& operator[](size_t address) { return data_[address]; }
  const uint8_t& operator[](size_t address) const { return data_[address]; }
  uint8_t* data() { return data_; }
  const uint8_t* data() const { return data_; }
  std::span<const uint8_t, kSize> view() const {
    return std::span<const uint8_t, kSize>(data_, kSize);
  }

 private:
  uint8_t* data_ = nullptr;
};

}  // namespace rackcat::ecat
