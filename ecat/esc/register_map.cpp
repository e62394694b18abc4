// Register write masks and the side effects of ECAT register accesses (ETG.1000.4 §6, ESC
// datasheet section II). Bytes not listed in the mask table are read-only for EtherCAT.
#include <array>

#include "base/little_endian.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

namespace {

struct MaskRange {
  uint16_t address;
  uint16_t length;
  uint8_t mask;
};

// ECAT-writable bits, one row per register (ESC datasheet "ECAT access" column). Registers
// whose write only triggers an action (error counters, SII command, DC latch and system time
// compare, ESC reset) have mask 0 here and are handled in after_register_write.
constexpr MaskRange kWritable[] = {
    {reg::kStationAddress, 2, 0xFF},
    {reg::kWriteEnable, 1, 0x01},
    {reg::kWriteProtection, 1, 0x01},
    {reg::kEscWriteEnable, 1, 0x01},
    {reg::kEscWriteProtection, 1, 0x01},
    {reg::kDlControl, 1, 0x03},      // forwarding rule, temporary loop control
    {reg::kDlControl + 1, 1, 0xFF},  // loop control ports 0-3
    {reg::kDlControl + 2, 1, 0x0F},  // RX FIFO size, EBUS low jitter
    {reg::kDlControl + 3, 1, 0x01},  // station alias enable
    {reg::kPhysicalRwOffset, 2, 0xFF},
    {reg::kAlControl, 1, 0x3F},  // state, error acknowledge, device identification request
    {reg::kRunLedOverride, 2, 0xFF},
    {reg::kEcatEventMask, 2, 0xFF},
    {reg::kWatchdogDivider, 2, 0xFF},
    {reg::kWatchdogTimePdi, 2, 0xFF},
    {reg::kWatchdogTimeProcessData, 2, 0xFF},
    {reg::kSiiConfig, 1, 0x01},  // bit 0 offer EEPROM to PDI; bit 1 (force ECAT) is an action
    {reg::kSiiAddress, 4, 0xFF},
    {reg::kSiiData, 8, 0xFF},
    {reg::kDcSystemTimeOffset, 8, 0xFF},
    {reg::kDcSystemTimeDelay, 4, 0xFF},
    {reg::kDcSpeedCounterStart, 1, 0xFF},
    {reg::kDcSpeedCounterStart + 1, 1, 0x7F},
    {reg::kDcFilterDepth, 2, 0x0F},
    {reg::kDcCyclicUnitControl, 1, 0x31},
    {reg::kDcActivation, 1, 0xFF},
    {reg::kDcStartTime, 8, 0xFF},
    {reg::kDcSync0Cycle, 8, 0xFF},
    {0x09A8, 2, 0x03},    // latch0/latch1 control
    {0x0F80, 128, 0xFF},  // user RAM
};

constexpr std::array<uint8_t, reg::kProcessRam> make_write_masks() {
  std::array<uint8_t, reg::kProcessRam> masks{};
  for (const auto& r : kWritable) {
    for (uint16_t i = 0; i < r.length; ++i) masks[r.address + i] = r.mask;
  }
  // FMMU n (ETG.1000.4 Table 56): logical start (4), length (2), logical start/stop bit
  // (3 bits each), physical start (2), physical start bit (3 bits), type (2 bits),
  // activate (1 bit), 3 reserved bytes.
  constexpr uint8_t kFmmuMasks[16] = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x07, 0x07,
                                      0xFF, 0xFF, 0x07, 0x03, 0x01, 0x00, 0x00, 0x00};
  for (int n = 0; n < Esc::kFmmus; ++n) {
    for (int i = 0; i < 16; ++i) masks[reg::kFmmu + reg::kFmmuSize * n + i] = kFmmuMasks[i];
  }
  // SyncManager n (ETG.1000.4 Table 58): start (2), length (2), control (7 bits), status (read
  // only), activate (enable, repeat request, latch ECAT/PDI), PDI control (read only). Bytes
  // 0-4 are only writable while the SyncManager is disabled (write_registers checks that).
  constexpr uint8_t kSmMasks[8] = {0xFF, 0xFF, 0xFF, 0xFF, 0x7F, 0x00, 0xC3, 0x00};
  for (int n = 0; n < Esc::kSyncManagers; ++n) {
    for (int i = 0; i < 8; ++i) masks[reg::kSm + reg::kSmSize * n + i] = kSmMasks[i];
  }
  return masks;
}

constexpr std::array<uint8_t, reg::kProcessRam> kWriteMask = make_write_masks();

constexpr bool overlaps(uint16_t address, uint16_t len, uint16_t reg_address, uint16_t reg_len) {
  return address < reg_address + reg_len && reg_address < address + len;
}

// ECAT event request bits cleared by reading the register they announce.
constexpr uint16_t kEventDlStatus = 0x0004;
constexpr uint16_t kEventAlStatus = 0x0008;
constexpr uint8_t kResetSequence[3] = {'R', 'E', 'S'};

}  // namespace

void Esc::write_registers(uint16_t address, const uint8_t* src, uint16_t len) {
  // The EEPROM interface's address and data are the PDI's while it holds the EEPROM;
  // SyncManager start/length/control can only be changed while the SM is disabled.
  const bool sii_pdi =
      overlaps(address, len, reg::kSiiAddress, reg::kSiiData + 8 - reg::kSiiAddress) &&
      sii_assigned_to_pdi();
  const bool sms = overlaps(address, len, reg::kSm, reg::kSmSize * kSyncManagers);
  uint8_t* const memory = mem_.data();
  if (!sii_pdi && !sms) {
    for (uint16_t i = 0; i < len; ++i) {
      const uint8_t mask = kWriteMask[address + i];
      memory[address + i] = static_cast<uint8_t>((memory[address + i] & ~mask) | (src[i] & mask));
    }
    return;
  }
  for (uint16_t i = 0; i < len; ++i) {
    const uint16_t a = static_cast<uint16_t>(address + i);
    uint8_t mask = kWriteMask[a];
    if (sii_pdi && a >= reg::kSiiAddress && a < reg::kSiiData + 8) mask = 0;
    if (sms && a >= reg::kSm && a < reg::kSm + reg::kSmSize * kSyncManagers && (a & 7) < 5 &&
        sm_[(a - reg::kSm) >> 3].enabled) {
      mask = 0;
    }
    memory[a] = static_cast<uint8_t>((memory[a] & ~mask) | (src[i] & mask));
  }
}

void Esc::after_register_write(uint16_t address, const uint8_t* src, uint16_t len) {
  if (address >= reg::kDcReceiveTimePort0) {
    dc_registers_written(address, src, len);
    return;
  }
  auto written = [&](uint16_t a) { return src[a - address]; };
  write_enables_written(address, src, len);
  if (overlaps(address, len, reg::kEscReset, 1)) {
    // ESC reset: 'R', 'E', 'S' written in three consecutive accesses (ESC datasheet 0x0040).
    const uint8_t byte = written(reg::kEscReset);
    if (byte == kResetSequence[reset_sequence_]) {
      if (++reset_sequence_ == 3) {
        power_on_reset();
        return;
      }
    } else {
      reset_sequence_ = byte == kResetSequence[0] ? 1 : 0;
    }
  }
  if (overlaps(address, len, reg::kDlControl, 4)) set_port1_link(port1_link_);
  if (overlaps(address, len, reg::kWriteProtection, 1) ||
      overlaps(address, len, reg::kEscWriteProtection, 1)) {
    derive_write_protection();
  }
  if (overlaps(address, len, reg::kWatchdogDivider, 2) ||
      overlaps(address, len, reg::kWatchdogTimeProcessData, 2)) {
    derive_watchdog_period();
  }
  if (overlaps(address, len, reg::kAlControl, 1)) {
    // AL control event (0x0220 bit 0, ESC datasheet): cleared when the PDI reads 0x0120.
    mem_[reg::kAlEventRequest] |= 0x01;
  }
  // Error counters: writing any RX error counter clears 0x0300-0x030B; the processing unit,
  // PDI and lost-link counters clear on their own write (ESC datasheet 0x0300-0x0313).
  if (overlaps(address, len, reg::kRxErrorCounter, 12)) {
    for (uint16_t a = reg::kRxErrorCounter; a < reg::kRxErrorCounter + 12; ++a) mem_[a] = 0;
  }
  if (overlaps(address, len, reg::kProcessingUnitError, 1)) mem_[reg::kProcessingUnitError] = 0;
  if (overlaps(address, len, reg::kPdiError, 1)) mem_[reg::kPdiError] = 0;
  if (overlaps(address, len, reg::kLostLinkCounter, 4)) {
    for (uint16_t a = reg::kLostLinkCounter; a < reg::kLostLinkCounter + 4; ++a) mem_[a] = 0;
  }
  if (overlaps(address, len, reg::kWatchdogCounterProcessData, 1)) {
    mem_[reg::kWatchdogCounterProcessData] = 0;
  }
  if (overlaps(address, len, reg::kWatchdogCounterPdi, 1)) mem_[reg::kWatchdogCounterPdi] = 0;
  if (overlaps(address, len, reg::kSiiConfig, 1) && (written(reg::kSiiConfig) & 0x02)) {
    mem_[reg::kSiiPdiAccess] &= 0xFE;  // force ECAT access: the PDI loses the EEPROM
  }
  if (overlaps(address, len, reg::kSiiControl + 1, 1) && !sii_assigned_to_pdi()) {
    // The command (bits 8-10) runs once the whole access is written, so the address written
    // in the same datagram (SOEM writes control + address together) is used.
    const bool lo = overlaps(address, len, reg::kSiiControl, 1);
    sii_command(lo ? written(reg::kSiiControl) : 0, written(reg::kSiiControl + 1) & 0x07, lo);
  }
  if (overlaps(address, len, reg::kFmmu, reg::kFmmuSize * kFmmus)) {
    for (int n = 0; n < kFmmus; ++n) {
      if (overlaps(address, len, static_cast<uint16_t>(reg::kFmmu + reg::kFmmuSize * n),
                   reg::kFmmuSize)) {
        reload_fmmu(n);
      }
    }
  }
  if (overlaps(address, len, reg::kSm, reg::kSmSize * kSyncManagers)) {
    for (int n = 0; n < kSyncManagers; ++n) {
      if (overlaps(address, len, static_cast<uint16_t>(reg::kSm + reg::kSmSize * n),
                   reg::kSmSize)) {
        reload_sm(n);
      }
    }
  }
  if (static_cast<uint32_t>(address) + len > reg::kDcReceiveTimePort0) {
    dc_registers_written(address, src, len);
  }
}

void Esc::dc_registers_written(uint16_t address, const uint8_t* src, uint16_t len) {
  // Distributed clocks 0x0900-0x09FF (ETG.1000.4 §6.8, ESC datasheet 0x0900-0x09B0).
  if (overlaps(address, len, reg::kDcReceiveTimePort0, 1)) dc_latch_receive_times();
  if (overlaps(address, len, reg::kDcSystemTime, 8)) dc_system_time_written(address, src, len);
  if (overlaps(address, len, reg::kDcSpeedCounterStart, 2)) {
    le::put16(&mem_[reg::kDcSpeedCounterDiff], 0);  // new start value resets the filters
  }
  if (overlaps(address, len, reg::kDcActivation, 1)) dc_activation_written();
  // A new system time offset moves the SYNC times (system time) in clock time.
  if (overlaps(address, len, reg::kDcSystemTimeOffset, 8) && (sync0_running_ || sync1_running_)) {
    timers_changed();
  }
}

void Esc::before_register_read(uint16_t address, uint16_t len) {
  if (overlaps(address, len, reg::kDcSystemTime, 8)) dc_prepare_system_time_read();
}

void Esc::after_register_read(uint16_t address, uint16_t len) {
  uint16_t events = le::get16(&mem_[reg::kEcatEventRequest]);
  if (overlaps(address, len, reg::kDlStatus, 2)) events &= ~kEventDlStatus;
  if (overlaps(address, len, reg::kAlStatus, 2)) events &= ~kEventAlStatus;
  le::put16(&mem_[reg::kEcatEventRequest], events);
}

}  // namespace rackcat::ecat
