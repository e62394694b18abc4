// Command objects 0xFBF0..0xFBF4 (ETG.5003.1 §"Command objects"; guide Appendix A): subindex 1
// takes the command bytes, 2 is the status, 3 the response (byte 0 = status, byte 1 = 0, then the
// command's result). Here the layout, the byte-sequence check (anything else: 0x06040043) and
// what a write does in a running device (attach_command_behaviour: the device executes the
// command, its worker does the file work, the status follows).
//
// Byte sequences: 0xFBF0 "reset" reversed (0x74 0x65 0x73 0x65 0x72) + 0x00 device reset /
// 0x66 factory reset; 0xFBF1 the same five bytes; 0xFBF2 "save" (0x73 0x61 0x76 0x65); 0xFBF3 one
// bit of byte 0 (bit 0 default algorithm, 1 CRC-32, 2 MD5, 3 SHA-1); 0xFBF4 "load" (0x6C 0x6F
// 0x61 0x64, ETG.5003.1; the guide's table for 0xFBF4 stops after the description).
#include <algorithm>
#include <array>
#include <functional>
#include <memory>

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
  o.edit_hooks().validate_write = [check](const Object& obj, int subindex,
                                          std::span<const uint8_t> data, EsmState) {
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

void complete_command(coe::ObjectDictionary& od, uint16_t index, uint8_t status,
                      std::span<const uint8_t> response) {
  Object* o = od.find(index);
  if (o == nullptr) return;
  o->set_u(2, status);
  auto resp = o->bytes(3);
  std::fill(resp.begin(), resp.end(), 0);
  if (!resp.empty()) resp[0] = status;
  for (size_t i = 0; i < response.size() && i + 2 < resp.size(); ++i) resp[i + 2] = response[i];
}

void restore_command(Object& obj) {
  const auto& def = obj.entry(1)->default_value;
  auto cmd = obj.bytes(1);
  std::fill(cmd.begin(), cmd.end(), 0);
  std::copy_n(def.begin(), std::min(cmd.size(), def.size()), cmd.begin());
}

namespace {

// A command executed in validate_write, applied to its object in after_write.
struct PendingCommand {
  uint8_t status = 0;
  bool executed = false;  // the write carried a command (not a write-back)
};

// Status and response of the command just written, and subindex 1 back to its read value.
void finish_command(Object& obj, const PendingCommand& pending) {
  obj.set_u(2, pending.status);
  auto resp = obj.bytes(3);
  std::fill(resp.begin(), resp.end(), 0);
  if (!resp.empty()) resp[0] = pending.status;
  restore_command(obj);
}

// Wraps the byte-sequence check of a command object with `execute`, run once the bytes are
// accepted (it returns the status to report); `apply` runs after the write is committed.
void command_hooks(coe::ObjectDictionary& od, uint16_t index,
                   const std::shared_ptr<PendingCommand>& pending,
                   std::function<uint8_t(std::span<const uint8_t>)> execute,
                   std::function<void(Object&, PendingCommand&)> apply) {
  Object* o = od.find(index);
  auto check = o->hooks().validate_write;
  o->edit_hooks().validate_write = [check, pending, execute = std::move(execute)](
                                       const Object& obj, int subindex,
                                       std::span<const uint8_t> data, EsmState s) {
    if (AbortCode rc = check(obj, subindex, data, s); rc != AbortCode::None) return rc;
    *pending = PendingCommand{};
    const auto cmd_bytes =
        subindex == 1    ? data
        : subindex == -1 ? data.subspan(obj.entry(1)->bit_offset / 8, obj.entry(1)->byte_length())
                         : std::span<const uint8_t>{};
    // A complete access writing back what it read (the check lets that pass) carries no
    // command.
    const auto current = obj.bytes(1);
    if (cmd_bytes.empty() || (subindex == -1 && std::equal(cmd_bytes.begin(), cmd_bytes.end(),
                                                           current.begin(), current.end()))) {
      return AbortCode::None;
    }
    pending->executed = true;
    pending->status = execute(cmd_bytes);
    return AbortCode::None;
  };
  o->edit_hooks().after_write = [pending, apply = std::move(apply)](Object& obj, int) {
    if (pending->executed) apply(obj, *pending);
    pending->executed = false;
  };
}

}  // namespace

void attach_command_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device) {
  auto pending = std::make_shared<PendingCommand>();
  auto finish = [](Object& obj, PendingCommand& p) { finish_command(obj, p); };
  // 0xFBF0 device / factory reset. The worker deletes (factory) and reads back the stored
  // file; the device then resets every object and tells its listeners (the adapter restarts
  // the ESC side once the master has read the answer).
  command_hooks(
      od, 0xFBF0, pending,
      [&device](std::span<const uint8_t> c) {
        device.start_device_reset(c[5] == cmd::kFactoryReset);
        return cmd::kStatusExecuting;
      },
      finish);
  // 0xFBF1 exception reset.
  command_hooks(
      od, 0xFBF1, pending, [](std::span<const uint8_t>) { return cmd::kStatusDoneNoResponse; },
      [&device](Object& obj, PendingCommand& p) {
        device.reset_exceptions();
        p.status = cmd::kStatusDoneNoResponse;
        finish_command(obj, p);
      });
  // 0xFBF2 store: the snapshot is taken now, written by the worker (status 255 until done).
  command_hooks(
      od, 0xFBF2, pending,
      [&device](std::span<const uint8_t>) {
        device.start_store();
        return cmd::kStatusExecuting;
      },
      finish);
  // 0xFBF3 checksum over the parameters as stored once the commands before it are done (the
  // shipped defaults when nothing valid is stored), computed by the worker.
  command_hooks(
      od, 0xFBF3, pending,
      [&device](std::span<const uint8_t> c) {
        device.start_checksum(c[0] == cmd::kChecksumDefault ? cmd::kChecksumMd5 : c[0]);
        return cmd::kStatusExecuting;
      },
      finish);
  // 0xFBF4 load: the stored file, or the shipped defaults when nothing is stored; read by the
  // worker, checked and applied when it has finished.
  command_hooks(
      od, 0xFBF4, pending,
      [&device](std::span<const uint8_t>) {
        device.start_load();
        return cmd::kStatusExecuting;
      },
      finish);
  // Reading a command whose job runs shows its status once the worker has finished.
  for (uint16_t index : {0xFBF0, 0xFBF2, 0xFBF3, 0xFBF4}) {
    od.find(index)->edit_hooks().before_read = [&device](Object&, int) {
      device.complete_commands();
    };
  }
}

}  // namespace rackcat::mdp
