// An ENI's CoE init commands (ETG.2100 Mailbox/CoE/InitCmds) replayed against the device the
// ENI builds, as the master will send them on its way to OP: each one an SDO download
// (ETG.1000.6 §5.6.2.1 normal transfer, complete access when the command says so) through the
// device's own coe::SdoServer, on a copy of its dictionary with the device's PDO checks
// (device/pdo_checks.hpp). The first SDO abort is the ENI's error at that command's line, so
// `rackcat check --eni` tells what the master would meet at start-up.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "base/esm_state.hpp"
#include "coe/object_dictionary.hpp"
#include "device/esi_device.hpp"

namespace rackcat::apps {

struct SdoWrite {
  size_t line = 0;                   // the InitCmd's line in the ENI
  EsmState state = EsmState::PreOp;  // the state the master sends it in
  uint16_t index = 0;
  uint8_t subindex = 0;
  bool complete_access = false;
  std::vector<uint8_t> data;
};

// Replays `writes` in order; returns the dictionary after them. Throws device::FileError
// (`file`, the write's line, "... SDO abort 0x06020000 (object does not exist) ...").
coe::ObjectDictionary replay_sdo_writes(const device::EsiDevice& dev,
                                        const std::vector<SdoWrite>& writes,
                                        const std::string& file);

}  // namespace rackcat::apps
