#include "ecat/al_status_code.hpp"

#include <algorithm>
#include <array>
#include <utility>

namespace rackcat::ecat {

namespace {

// ETG.1000.6 Table 11 (AL status codes) with the ETG.1020 additions masters print.
constexpr std::array<std::pair<uint16_t, std::string_view>, 52> kNames{{
    {0x0000, "No error"},
    {0x0001, "Unspecified error"},
    {0x0002, "No memory"},
    {0x0003, "Invalid device setup"},
    {0x0011, "Invalid requested state change"},
    {0x0012, "Unknown requested state"},
    {0x0013, "Bootstrap not supported"},
    {0x0014, "No valid firmware"},
    {0x0015, "Invalid mailbox configuration (BOOT)"},
    {0x0016, "Invalid mailbox configuration (PREOP)"},
    {0x0017, "Invalid sync manager configuration"},
    {0x0018, "No valid inputs available"},
    {0x0019, "No valid outputs"},
    {0x001A, "Synchronization error"},
    {0x001B, "Sync manager watchdog"},
    {0x001C, "Invalid sync manager types"},
    {0x001D, "Invalid output configuration"},
    {0x001E, "Invalid input configuration"},
    {0x001F, "Invalid watchdog configuration"},
    {0x0020, "Slave needs cold start"},
    {0x0021, "Slave needs INIT"},
    {0x0022, "Slave needs PREOP"},
    {0x0023, "Slave needs SAFEOP"},
    {0x0024, "Invalid input mapping"},
    {0x0025, "Invalid output mapping"},
    {0x0026, "Inconsistent settings"},
    {0x0027, "FreeRun not supported"},
    {0x0028, "SyncMode not supported"},
    {0x0029, "FreeRun needs 3-buffer mode"},
    {0x002A, "Background watchdog"},
    {0x002B, "No valid inputs and outputs"},
    {0x002C, "Fatal sync error"},
    {0x002D, "No sync error"},
    {0x002E, "Cycle time too small"},
    {0x0030, "Invalid DC SYNC configuration"},
    {0x0031, "Invalid DC latch configuration"},
    {0x0032, "PLL error"},
    {0x0033, "DC sync IO error"},
    {0x0034, "DC sync timeout error"},
    {0x0035, "DC invalid sync cycle time"},
    {0x0036, "DC SYNC0 cycle time"},
    {0x0037, "DC SYNC1 cycle time"},
    {0x0041, "MBX_AOE"},
    {0x0042, "MBX_EOE"},
    {0x0043, "MBX_COE"},
    {0x0044, "MBX_FOE"},
    {0x0045, "MBX_SOE"},
    {0x004F, "MBX_VOE"},
    {0x0050, "EEPROM no access"},
    {0x0051, "EEPROM error"},
    {0x0060, "Slave restarted locally"},
    {0x0070, "Detected module ident list does not match"},
}};

}  // namespace

std::string_view al_status_code_name(uint16_t code) {
  const auto* it = std::lower_bound(kNames.begin(), kNames.end(), code,
                                    [](const auto& e, uint16_t c) { return e.first < c; });
  if (it != kNames.end() && it->first == code) return it->second;
  return "Unknown AL status code";
}

}  // namespace rackcat::ecat
