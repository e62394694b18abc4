// The host side of a Microchip LAN9252 (an ESC with an SPI/SQI host bus): the two SPI
// instructions a microcontroller uses to reach the chip's system registers (LAN9252 datasheet
// §5 "SPI/SQI slave", Table 5-1 "system control and status registers"):
//   serial read  0x03, address (2 bytes, big-endian), data...
//   serial write 0x02, address (2 bytes, big-endian), data...
// Data bytes are little-endian, as every register of the chip. The EtherCAT core's own
// registers and process RAM are not on this bus: they are reached indirectly through the
// system registers (lan9252_pdi.hpp). A transport carries these instructions: Linux spidev
// on a board (SpidevBus, ecat/host), or the chip model wrapped in the LAN9252's access
// protocol (EmulatedLan9252) in tests and `rackcat run --pdi lan9252-emulated`.
#pragma once

#include <cstdint>
#include <span>

namespace rackcat::ecat {

// LAN9252 system register addresses (datasheet Table 5-1).
namespace lan9252 {
inline constexpr uint16_t kPramReadFifo = 0x0000;   // 0x000-0x01F: process RAM read FIFO
inline constexpr uint16_t kPramWriteFifo = 0x0020;  // 0x020-0x03F: process RAM write FIFO
inline constexpr uint16_t kIdRev = 0x0050;
inline constexpr uint16_t kIrqCfg = 0x0054;
inline constexpr uint16_t kIntSts = 0x0058;
inline constexpr uint16_t kIntEn = 0x005C;
inline constexpr uint16_t kByteTest = 0x0064;  // reads 0x87654321
inline constexpr uint16_t kHwCfg = 0x0074;     // bit 27: device ready
inline constexpr uint16_t kResetCtl = 0x01F8;
inline constexpr uint16_t kCsrData = 0x0300;  // EtherCAT CSR interface data
inline constexpr uint16_t kCsrCmd =
    0x0304;  // ... command: busy 31, read 30, size 18:16, address 15:0
inline constexpr uint16_t kPramReadAddrLen = 0x0308;  // length 31:16, address 15:0
inline constexpr uint16_t kPramReadCmd = 0x030C;  // busy 31, abort 30, avail count 12:8, avail 0
inline constexpr uint16_t kPramWriteAddrLen = 0x0310;  // length 31:16, address 15:0
inline constexpr uint16_t kPramWriteCmd = 0x0314;  // busy 31, abort 30, space count 12:8, space 0

inline constexpr uint32_t kByteTestValue = 0x87654321;
inline constexpr uint32_t kHwCfgReady = 1u << 27;
inline constexpr uint32_t kCsrBusy = 1u << 31;
inline constexpr uint32_t kCsrRead = 1u << 30;
inline constexpr uint32_t kPramBusy = 1u << 31;
inline constexpr uint32_t kPramAbort = 1u << 30;
inline constexpr uint32_t kPramAvail = 1u << 0;
inline constexpr size_t kFifoDwords = 16;  // each PRAM FIFO holds 16 DWORDs (64 bytes)

inline constexpr uint8_t kSpiRead = 0x03;
inline constexpr uint8_t kSpiWrite = 0x02;
}  // namespace lan9252

class Lan9252Bus {
 public:
  virtual ~Lan9252Bus() = default;
  // Serial read / write of `data.size()` bytes at system register `address`.
  virtual void read(uint16_t address, std::span<uint8_t> data) = 0;
  virtual void write(uint16_t address, std::span<const uint8_t> data) = 0;
  // The chip's IRQ pin (IRQ_CFG: active while INT_STS & INT_EN, the EtherCAT interrupt being
  // AL event request & mask).
  virtual bool irq() const = 0;
};

}  // namespace rackcat::ecat
