// SDO Information service constants (ETG.1000.6 §5.6.3): opcodes, OD list types and the
// value-info bits of an entry description.
#pragma once

#include <cstddef>
#include <cstdint>

namespace rackcat::coe::sdo_info {

// SDO Information header: byte 0 = opcode (bits 0-6) + incomplete (bit 7), byte 1 reserved,
// bytes 2-3 = fragments left (§5.6.3.2).
inline constexpr uint8_t kGetOdListRequest = 0x01;
inline constexpr uint8_t kGetOdListResponse = 0x02;
inline constexpr uint8_t kGetObjectDescriptionRequest = 0x03;
inline constexpr uint8_t kGetObjectDescriptionResponse = 0x04;
inline constexpr uint8_t kGetEntryDescriptionRequest = 0x05;
inline constexpr uint8_t kGetEntryDescriptionResponse = 0x06;
inline constexpr uint8_t kErrorRequest = 0x07;
inline constexpr uint8_t kIncomplete = 0x80;
inline constexpr size_t kHeaderSize = 4;

// OD list types (§5.6.3.3.1 Table 44).
inline constexpr uint16_t kListLengths = 0;  // number of objects of each list 1..5
inline constexpr uint16_t kListAll = 1;      // all objects
inline constexpr uint16_t kListRxPdoMappable = 2;
inline constexpr uint16_t kListTxPdoMappable = 3;
inline constexpr uint16_t kListBackup = 4;    // stored for device replacement
inline constexpr uint16_t kListSettings = 5;  // startup parameters

// Value info of an entry description request/response (§5.6.3.6.1 Table 46).
inline constexpr uint8_t kValueUnitType = 0x08;
inline constexpr uint8_t kValueDefault = 0x10;
inline constexpr uint8_t kValueMinimum = 0x20;
inline constexpr uint8_t kValueMaximum = 0x40;

}  // namespace rackcat::coe::sdo_info
