// SDO abort code descriptions: the Fusion.IO guide's Appendix C (Table 25), which follows
// ETG.1000.6 §5.6.2.7.2 Table 41; 0x06040047 and 0x08000023 come from ETG.1000.6 only.
#include "coe/abort_code.hpp"

#include <array>

namespace rackcat::coe {
namespace {

struct AbortText {
  AbortCode code;
  std::string_view text;
};

constexpr std::array<AbortText, 30> kAbortTexts{{
    {AbortCode::None, "No SDO error"},
    {AbortCode::ToggleBit, "Toggle bit not changed"},
    {AbortCode::Timeout, "SDO protocol timeout"},
    {AbortCode::CommandSpecifier, "Client/Server command specifier not valid or unknown"},
    {AbortCode::OutOfMemory, "Out of memory"},
    {AbortCode::UnsupportedAccess, "Unsupported access to an object"},
    {AbortCode::WriteOnly, "Attempt to read from a write only object"},
    {AbortCode::ReadOnly, "Attempt to write to a read only object"},
    {AbortCode::SubindexZeroNotZero, "Entry cannot be written because Subindex0 is not 0"},
    {AbortCode::CompleteAccessUnsupported, "The object cannot be accessed via complete access"},
    {AbortCode::ObjectNotFound, "The object does not exist in the object dictionary"},
    {AbortCode::NotMappable, "The object cannot be mapped to PDO"},
    {AbortCode::PdoLengthExceeded,
     "The number and length of the objects to be mapped would exceed the PDO length"},
    {AbortCode::ParameterIncompatible, "General parameter incompatibility reason"},
    {AbortCode::DeviceIncompatible, "General internal incompatibility in the device"},
    {AbortCode::HardwareError, "Access failed due to a hardware error"},
    {AbortCode::LengthMismatch,
     "Data type does not match, length of service parameter does not match"},
    {AbortCode::LengthTooHigh, "Data type does not match, length of service parameter too high"},
    {AbortCode::LengthTooLow, "Data type does not match, length of service parameter too low"},
    {AbortCode::SubindexNotFound, "Subindex does not exist"},
    {AbortCode::ValueRange, "Value range of parameter exceeded (only for write access)"},
    {AbortCode::ValueTooHigh, "Value of parameter written too high"},
    {AbortCode::ValueTooLow, "Value of parameter written too low"},
    {AbortCode::ModuleListMismatch,
     "Detected Module Ident List (0xF030) and Configured Module Ident list (0xF050) do not "
     "match"},
    {AbortCode::MaxBelowMin, "Maximum value is less than minimum value"},
    {AbortCode::GeneralError, "General error"},
    {AbortCode::CannotTransfer, "Data cannot be read or written"},
    {AbortCode::LocalControl, "Data cannot be accessed because of local control"},
    {AbortCode::DeviceState, "Data cannot be read or written in the device's current state"},
    {AbortCode::NoDictionary,
     "Object dictionary dynamic generation fails or no object dictionary is present"},
}};

}  // namespace

std::string_view describe(AbortCode code) {
  for (const auto& a : kAbortTexts) {
    if (a.code == code) {
      return a.text;
    }
  }
  return "Unknown SDO abort code";
}

}  // namespace rackcat::coe
