// LAN9252 indirect access: CSR interface for the ESC registers, PRAM FIFOs for process RAM
// (LAN9252 datasheet, "EtherCAT CSR and process data RAM access").
#include "ecat/lan9252/lan9252_pdi.hpp"

#include <algorithm>

#include "base/little_endian.hpp"

namespace rackcat::ecat {

namespace {

constexpr uint32_t kProcessRam = 0x1000;  // first byte behind the CSR interface's reach

// The largest naturally aligned CSR access (4, 2 or 1 bytes) at `address` within `left`.
uint8_t csr_chunk(uint32_t address, uint32_t left) {
  if ((address & 3) == 0 && left >= 4) return 4;
  if ((address & 1) == 0 && left >= 2) return 2;
  return 1;
}

}  // namespace

uint32_t Lan9252Pdi::sys_read(uint16_t address) {
  uint8_t b[4];
  bus_.read(address, b);
  ++transactions_;
  return le::get32(b);
}

void Lan9252Pdi::sys_write(uint16_t address, uint32_t value) {
  uint8_t b[4];
  le::put32(b, value);
  bus_.write(address, b);
  ++transactions_;
}

bool Lan9252Pdi::start() {
  if (sys_read(lan9252::kByteTest) != lan9252::kByteTestValue) return false;
  if ((sys_read(lan9252::kHwCfg) & lan9252::kHwCfgReady) == 0) return false;
  sys_write(lan9252::kIntEn, 0x00000001);   // EtherCAT interrupt to the IRQ pin
  sys_write(lan9252::kIrqCfg, 0x00000100);  // IRQ_EN
  return true;
}

void Lan9252Pdi::csr_read(uint16_t address, uint8_t* dst, uint8_t size) {
  sys_write(lan9252::kCsrCmd,
            lan9252::kCsrBusy | lan9252::kCsrRead | (static_cast<uint32_t>(size) << 16) | address);
  while (sys_read(lan9252::kCsrCmd) & lan9252::kCsrBusy) {
  }
  uint8_t b[4];
  bus_.read(lan9252::kCsrData, b);
  ++transactions_;
  std::copy_n(b, size, dst);
}

void Lan9252Pdi::csr_write(uint16_t address, const uint8_t* src, uint8_t size) {
  uint8_t b[4] = {0, 0, 0, 0};
  std::copy_n(src, size, b);
  bus_.write(lan9252::kCsrData, b);
  ++transactions_;
  sys_write(lan9252::kCsrCmd, lan9252::kCsrBusy | (static_cast<uint32_t>(size) << 16) | address);
  while (sys_read(lan9252::kCsrCmd) & lan9252::kCsrBusy) {
  }
}

void Lan9252Pdi::pram_read(uint16_t address, uint8_t* dst, uint16_t len) {
  sys_write(lan9252::kPramReadCmd, lan9252::kPramAbort);
  sys_write(lan9252::kPramReadAddrLen, static_cast<uint32_t>(len) << 16 | address);
  sys_write(lan9252::kPramReadCmd, lan9252::kPramBusy);
  size_t lane = address & 3;  // the first DWORD starts at the address's byte lane
  uint16_t done = 0;
  while (done < len) {
    uint32_t avail = 0;
    while (((avail = sys_read(lan9252::kPramReadCmd)) & lan9252::kPramAvail) == 0) {
    }
    const uint32_t dwords = std::max<uint32_t>((avail >> 8) & 0x1F, 1);
    for (uint32_t i = 0; i < dwords && done < len; ++i) {
      uint8_t b[4];
      bus_.read(lan9252::kPramReadFifo, b);
      ++transactions_;
      const auto n = static_cast<uint16_t>(std::min<size_t>(4 - lane, len - done));
      std::copy_n(b + lane, n, dst + done);
      done = static_cast<uint16_t>(done + n);
      lane = 0;
    }
  }
}

void Lan9252Pdi::pram_write(uint16_t address, const uint8_t* src, uint16_t len) {
  sys_write(lan9252::kPramWriteCmd, lan9252::kPramAbort);
  sys_write(lan9252::kPramWriteAddrLen, static_cast<uint32_t>(len) << 16 | address);
  sys_write(lan9252::kPramWriteCmd, lan9252::kPramBusy);
  size_t lane = address & 3;
  uint16_t done = 0;
  while (done < len) {
    uint32_t space = 0;
    while (((space = sys_read(lan9252::kPramWriteCmd)) & lan9252::kPramAvail) == 0) {
    }
    const uint32_t dwords = std::max<uint32_t>((space >> 8) & 0x1F, 1);
    for (uint32_t i = 0; i < dwords && done < len; ++i) {
      uint8_t b[4] = {0, 0, 0, 0};
      const auto n = static_cast<uint16_t>(std::min<size_t>(4 - lane, len - done));
      std::copy_n(src + done, n, b + lane);
      bus_.write(lan9252::kPramWriteFifo, b);
      ++transactions_;
      done = static_cast<uint16_t>(done + n);
      lane = 0;
    }
  }
}

void Lan9252Pdi::read(uint16_t address, std::span<uint8_t> dst) {
  uint32_t a = address;
  size_t i = 0;
  while (i < dst.size() && a < kProcessRam) {
    const uint8_t n =
        csr_chunk(a, static_cast<uint32_t>(std::min<size_t>(dst.size() - i, kProcessRam - a)));
    csr_read(static_cast<uint16_t>(a), &dst[i], n);
    a += n;
    i += n;
  }
  if (i < dst.size()) {
    pram_read(static_cast<uint16_t>(a), &dst[i], static_cast<uint16_t>(dst.size() - i));
  }
}

void Lan9252Pdi::write(uint16_t address, std::span<const uint8_t> src) {
  uint32_t a = address;
  size_t i = 0;
  while (i < src.size() && a < kProcessRam) {
    const uint8_t n =
        csr_chunk(a, static_cast<uint32_t>(std::min<size_t>(src.size() - i, kProcessRam - a)));
    csr_write(static_cast<uint16_t>(a), &src[i], n);
    a += n;
    i += n;
  }
  if (i < src.size()) {
    pram_write(static_cast<uint16_t>(a), &src[i], static_cast<uint16_t>(src.size() - i));
  }
}

void Lan9252Pdi::read_buffer(uint8_t /*sm*/, uint16_t address, std::span<uint8_t> dst) {
  if (address < kProcessRam || dst.empty()) {
    read(address, dst);
    return;
  }
  pram_read(address, dst.data(), static_cast<uint16_t>(dst.size()));
}

void Lan9252Pdi::write_buffer(uint8_t /*sm*/, uint16_t address, std::span<const uint8_t> src) {
  if (address < kProcessRam || src.empty()) {
    write(address, src);
    return;
  }
  pram_write(address, src.data(), static_cast<uint16_t>(src.size()));
}

}  // namespace rackcat::ecat
