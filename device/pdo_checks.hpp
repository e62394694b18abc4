// The checks a device from its ESI applies to SDO writes of its PDO configuration (ETG.1000.6
// §5.6.7.4.7 mapping, §5.6.7.4.9 assignment): coe::install_pdo_validators on 0x1C12/0x1C13 and
// every mapping object, bounded by the process-data SMs' MaxSize. A master (or an ENI's init
// commands) assigning a PDO the device lacks, or more than its SM holds, gets the SDO abort.
#pragma once

#include "coe/object_dictionary.hpp"
#include "esi/device_description.hpp"

namespace rackcat::device {

// The most process data an SM may carry when its ESI gives no MaxSize: the ESC's process RAM
// above 0x1000 (ETG.1000.4 §6.7.1: SM start addresses are 16-bit).
inline constexpr size_t kUnboundedSmBytes = 0xF000;

// Installs the validators on `od` (hooks refer to `od`: call again on a copy).
void install_pdo_checks(coe::ObjectDictionary& od, const esi::DeviceDescription& d);

}  // namespace rackcat::device
