// SDO abort codes (ETG.1000.6 §5.6.2.7.2 Table 41; Fusion.IO guide Appendix C, Table 25).
#pragma once

#include <cstdint>
#include <string_view>

namespace rackcat::coe {

enum class AbortCode : uint32_t {
  None = 0,
  ToggleBit = 0x05030000,
  Timeout = 0x05040000,
  CommandSpecifier = 0x05040001,
  OutOfMemory = 0x05040005,
  UnsupportedAccess = 0x06010000,
  WriteOnly = 0x06010001,
  ReadOnly = 0x06010002,
  SubindexZeroNotZero = 0x06010003,  // complete access: subindex 0 must be 0 to write
  CompleteAccessUnsupported = 0x06010004,
  ObjectNotFound = 0x06020000,
  NotMappable = 0x06040041,
  PdoLengthExceeded = 0x06040042,
  ParameterIncompatible = 0x06040043,
  DeviceIncompatible = 0x06040047,
  HardwareError = 0x06060000,
  LengthMismatch = 0x06070010,
  LengthTooHigh = 0x06070012,
  LengthTooLow = 0x06070013,
  SubindexNotFound = 0x06090011,
  ValueRange = 0x06090030,
  ValueTooHigh = 0x06090031,
  ValueTooLow = 0x06090032,
  ModuleListMismatch = 0x06090033,
  MaxBelowMin = 0x06090036,
  GeneralError = 0x08000000,
  CannotTransfer = 0x08000020,
  LocalControl = 0x08000021,
  DeviceState = 0x08000022,
  NoDictionary = 0x08000023,
};

// The guide's description text for a code ("Toggle bit not changed", ...).
std::string_view describe(AbortCode code);

}  // namespace rackcat::coe
