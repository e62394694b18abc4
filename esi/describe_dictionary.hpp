// Derives the DeviceDescription the SII and the ESI are written from, out of the live object
// dictionary: identity from 0x1018, the device name from 0x1008, the PDOs from the mapping
// objects 0x1600..0x17FF / 0x1A00..0x1BFF and the assignment 0x1C12/0x1C13, and the
// process-data SM sizes from that assignment. Nothing about the device is restated here, so
// the EEPROM, the ESI and what a master reads over CoE agree by construction.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "coe/object_dictionary.hpp"
#include "esi/device_description.hpp"

namespace rackcat::esi {

// The fixed SyncManager plan of the device (mdp/sync_manager_layout.hpp for the rack).
struct SmPlan {
  uint16_t mailbox_out_start = 0x1000, mailbox_out_size = 128;
  uint8_t mailbox_out_control = 0x26;
  uint16_t mailbox_in_start = 0x1080, mailbox_in_size = 128;
  uint8_t mailbox_in_control = 0x22;
  uint16_t outputs_start = 0x1100;
  uint8_t outputs_control = 0x64;
  uint16_t inputs_start = 0x5100;
  uint8_t inputs_control = 0x20;
  uint16_t max_process_data_bytes = 0x4000;
  bool foe = false;
  uint16_t boot_out_start = 0, boot_out_size = 0;  // bootstrap mailbox; sizes 0: no BOOT
  uint16_t boot_in_start = 0, boot_in_size = 0;
};

// Texts the dictionary does not carry (or carries under a device-specific index).
struct DeviceTexts {
  std::string vendor_name;
  std::string order_code;
  std::string group_type;
  std::string group_name;
};

class DescribeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws DescribeError when 0x1018 is missing or a PDO assignment names a mapping object that
// does not exist (the dictionary itself would then be inconsistent).
DeviceDescription describe_dictionary(const coe::ObjectDictionary& od, const DeviceTexts& texts,
                                      const SmPlan& plan);

// The PDO (index, name, entries, fixed flag) described by mapping object `mapping` of `od`;
// `sm` is the SyncManager it belongs to. Entry names and types come from the mapped objects.
PdoDescription describe_pdo(const coe::ObjectDictionary& od, const coe::Object& mapping,
                            uint8_t sm);

// The bytes a set of assigned PDOs occupies in its SM (bits rounded up to bytes).
uint16_t pdo_bytes(const std::vector<PdoDescription>& pdos);

}  // namespace rackcat::esi
