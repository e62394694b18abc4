// CoE basic data types (ETG.1000.6 §5.6.7.4.4, Table 63 "Basic Data Type Area").
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>

namespace rackcat::coe {

// Data type indices as they appear in the object dictionary (0x0001..0x0037) and in
// SDO Information entry descriptions. Enumerated types of a device live at 0x0800+
// (the Fusion.IO guide's DT0800EN04 ... DT0805EN..).
enum class DataType : uint16_t {
  Boolean = 0x0001,
  Integer8 = 0x0002,
  Integer16 = 0x0003,
  Integer32 = 0x0004,
  Unsigned8 = 0x0005,
  Unsigned16 = 0x0006,
  Unsigned32 = 0x0007,
  Real32 = 0x0008,
  VisibleString = 0x0009,
  OctetString = 0x000A,
  UnicodeString = 0x000B,
  Integer24 = 0x0010,
  Real64 = 0x0011,
  Integer64 = 0x0015,
  Unsigned24 = 0x0016,
  Unsigned64 = 0x001B,
  Bit1 = 0x0030,
  Bit2 = 0x0031,
  Bit3 = 0x0032,
  Bit4 = 0x0033,
  Bit5 = 0x0034,
  Bit6 = 0x0035,
  Bit7 = 0x0036,
  Bit8 = 0x0037,
};

// Standard record types of the communication area (ETG.1000.6 §5.6.7.4.5, "Complex Data Type
// Area" 0x0020..0x002F): the data type SDO Information gives a RECORD object that uses one.
namespace record_type {
inline constexpr uint16_t kPdoMapping = 0x0021;
inline constexpr uint16_t kSdoParameter = 0x0022;
inline constexpr uint16_t kIdentity = 0x0023;
inline constexpr uint16_t kCommandPar = 0x0025;
inline constexpr uint16_t kPdoParameter = 0x0027;
inline constexpr uint16_t kEnum = 0x0028;
inline constexpr uint16_t kSmSynchronisation = 0x0029;
inline constexpr uint16_t kRecord = 0x002A;  // any other record
inline constexpr uint16_t kBackupParameter = 0x002B;
inline constexpr uint16_t kModularDeviceProfile = 0x002C;
}  // namespace record_type

// True for indices 0x0800..0x0FFF: device-specific enumerations (ETG.1000.6 §5.6.7.4.4).
constexpr bool is_enum_type(uint16_t index) {
  return index >= 0x0800 && index <= 0x0FFF;
}

// Fixed bit size of a basic type; nullopt for strings (size given per entry).
std::optional<uint16_t> fixed_bit_size(DataType t);
// The ETG.2000 / ETG.1000.6 name: "BOOL", "SINT", "INT", "DINT", "USINT", "UINT", "UDINT",
// "REAL", "STRING(n)" base "STRING", "OCTET_STRING", "UNICODE_STRING", "INT24", "LREAL", "LINT",
// "UINT24", "ULINT", "BIT1".."BIT8".
std::string_view type_name(DataType t);
bool is_signed(DataType t);
bool is_real(DataType t);
bool is_string(DataType t);  // visible, octet, unicode

}  // namespace rackcat::coe
