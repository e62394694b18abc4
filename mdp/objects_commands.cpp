// Command objects 0xFBF0..0xFBF4 (ETG.5003.1 §"Command objects"; guide Appendix A): subindex 1
// takes the command bytes, 2 is the status, 3 the response (byte 0 = status, byte 1 = 0, then the
// command's result). Here only the layout and the byte-sequence check (anything else:
// 0x06040043); mdp::Device executes the commands after the write.
//
// Byte sequences: 0xFBF0 "reset" reversed (0x74 0x65 0x73 0x65 0x72) + 0x00 device reset /
// 0x66 factory reset; 0xFBF1 the same five bytes; 0xFBF2 "save" (0x73 0x61 0x76 0x65); 0xFBF3 one
// bit of byte 0 (bit 0 default algorithm, 1 CRC-32, 2 MD5, 3 SHA-1); 0xFBF4 "load" (0x6C 0x6F
// 0x61 0x64, ETG.5003.1; the guide's table for 0xFBF4 stops after the description).
#include <algorithm>
#include <array>

#include "mdp/command_bytes.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;
using coe::AbortCode;

Object command(uint16_t index, const char* name, uint16_t command_bytes,
               std::span<const uint8_t> command_default, uint16_t response_bytes,
               AbortCode (*check)(std::span<const uint8_t>)) {
  Object o(index, ObjectCode::Record, name, coe::record_type::kCommandPar);
  o.add(sub0(3));
  o.add(octets(1, "Command", command_bytes, acc("rw"), command_default));
  o.add(num(2, "Status", DataType::Unsigned8, acc("ro"), 0));
  o.add(octets(3, "Response", response_bytes, acc("ro")));
  o.finalize();
  o.hooks.validate_write = [check](const Object& obj, int subindex, std::span<const uint8_t> data,
                                   EsmState) {
    const auto cmd = written_bytes(obj, 1, subindex, data);
    if (cmd.empty()) return AbortCode::None;
    if (subindex == -1 && std::equal(cmd.begin(), cmd.end(), obj.bytes(1).begin())) {
      return AbortCode::None;  // complete access writing back what it read
    }
    return check(cmd);
  };
  return o;
}

template <size_t N>
bool starts_with(std::span<const uint8_t> data, const std::array<uint8_t, N>& prefix) {
  return data.size() >= N && std::equal(prefix.begin(), prefix.end(), data.begin());
}

AbortCode check_reset(std::span<const uint8_t> d) {
  return d.size() == 6 && starts_with(d, cmd::kReset) &&
                 (d[5] == cmd::kDeviceReset || d[5] == cmd::kFactoryReset)
             ? AbortCode::None
             : AbortCode::ParameterIncompatible;
}
AbortCode check_exception_reset(std::span<const uint8_t> d) {
  return d.size() == 5 && starts_with(d, cmd::kReset) ? AbortCode::None
                                                      : AbortCode::ParameterIncompatible;
}
AbortCode check_store(std::span<const uint8_t> d) {
  return d.size() == 4 && starts_with(d, cmd::kSave) ? AbortCode::None
                                                     : AbortCode::ParameterIncompatible;
}
AbortCode check_load(std::span<const uint8_t> d) {
  return d.size() == 4 && starts_with(d, cmd::kLoad) ? AbortCode::None
                                                     : AbortCode::ParameterIncompatible;
}
AbortCode check_checksum(std::span<const uint8_t> d) {
  if (d.size() != 4 || d[1] || d[2] || d[3]) return AbortCode::ParameterIncompatible;
  // Exactly one bit, and one of the algorithms offered (bits 0..3).
  const uint8_t b = d[0];
  const bool one_bit = b != 0 && (b & (b - 1)) == 0;
  return one_bit && b <= cmd::kChecksumSha1 ? AbortCode::None : AbortCode::ParameterIncompatible;
}

}  // namespace

void add_command_objects(const RackConfig&, coe::ObjectDictionary& od) {
  static constexpr std::array<uint8_t, 6> kNone6{};
  static constexpr std::array<uint8_t, 5> kNone5{};
  od.add(command(0xFBF0, "Device Reset Command", 6, kNone6, 2, check_reset));
  od.add(command(0xFBF1, "Exception Reset Command", 5, kNone5, 2, check_exception_reset));
  od.add(command(0xFBF2, "Store Parameters Command", 4, cmd::kStoreCapabilities, 2, check_store));
  od.add(command(0xFBF3, "Calculate Checksum Command", 4, cmd::kChecksumCapabilities,
                 cmd::kChecksumResponseBytes, check_checksum));
  od.add(command(0xFBF4, "Load Parameters Command", 4, cmd::kLoadCapabilities, 2, check_load));
}

}  // namespace rackcat::mdp
