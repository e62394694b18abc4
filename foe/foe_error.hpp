// FoE error codes and their standard texts (ETG.1000.5 §6.4 / ETG.1000.6 §5.8 "FoE Error",
// Table "FoE error codes"): 0x8000..0x800B as ETG.1000.6 lists them, 0x800C..0x8012 as the
// later revisions of the table add them (the values the EtherCAT slave stack code and the
// common masters decode). An FoE Error request carries the code (UINT32) and may carry the text.
#pragma once

#include <cstdint>
#include <string_view>

namespace rackcat::foe {

enum class FoeError : uint32_t {
  None = 0,  // not on the wire: "no error"
  NotDefined = 0x8000,
  NotFound = 0x8001,
  AccessDenied = 0x8002,
  DiskFull = 0x8003,
  Illegal = 0x8004,
  PacketNumberWrong = 0x8005,
  AlreadyExists = 0x8006,
  NoUser = 0x8007,
  BootstrapOnly = 0x8008,
  NotBootstrap = 0x8009,
  NoRights = 0x800A,
  ProgramError = 0x800B,
  WrongChecksum = 0x800C,
  FirmwareDoesNotFitHardware = 0x800D,
  NoFileToRead = 0x800F,
  FileHeaderDoesNotExist = 0x8010,
  FlashProblem = 0x8011,
  FileIncompatible = 0x8012,
};

// The standard text of `error` ("Not found", "Packet number wrong", ...); "Unknown FoE error"
// for a value the table does not list.
std::string_view describe(FoeError error);

}  // namespace rackcat::foe
