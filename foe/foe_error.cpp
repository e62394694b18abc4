// Standard FoE error texts (ETG.1000.6 §5.8, table of FoE error codes).
#include "foe/foe_error.hpp"

namespace rackcat::foe {

std::string_view describe(FoeError error) {
  switch (error) {
    case FoeError::None:
      return "No error";
    case FoeError::NotDefined:
      return "Not defined";
    case FoeError::NotFound:
      return "Not found";
    case FoeError::AccessDenied:
      return "Access denied";
    case FoeError::DiskFull:
      return "Disk full";
    case FoeError::Illegal:
      return "Illegal";
    case FoeError::PacketNumberWrong:
      return "Packet number wrong";
    case FoeError::AlreadyExists:
      return "Already exists";
    case FoeError::NoUser:
      return "No user";
    case FoeError::BootstrapOnly:
      return "Bootstrap only";
    case FoeError::NotBootstrap:
      return "Not Bootstrap";
    case FoeError::NoRights:
      return "No rights";
    case FoeError::ProgramError:
      return "Program Error";
    case FoeError::WrongChecksum:
      return "Wrong checksum";
    case FoeError::FirmwareDoesNotFitHardware:
      return "Firmware does not fit for hardware";
    case FoeError::NoFileToRead:
      return "No file to read";
    case FoeError::FileHeaderDoesNotExist:
      return "File header does not exist";
    case FoeError::FlashProblem:
      return "Flash problem";
    case FoeError::FileIncompatible:
      return "File incompatible";
  }
  return "Unknown FoE error";
}

}  // namespace rackcat::foe
