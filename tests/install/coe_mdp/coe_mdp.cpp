// Uses the installed MDP layer as a device maker would: the built-in default rack as an
// mdp::Device, and one expedited SDO upload of 0x1018:02 (identity object, product code;
// ETG.1000.6 §5.6.2.2) through its CoE (the data of one mailbox message). Exit 0 when the
// reply is an expedited upload response of 4 bytes (command 0x43) for 0x1018:02 with a
// product code.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "mdp/device.hpp"
#include "mdp/rack_config.hpp"

int main() {
  using namespace rackcat;
  char dir[] = "/tmp/coe_mdp.XXXXXX";
  if (::mkdtemp(dir) == nullptr) return 1;
  mdp::DeviceOptions options;
  options.state_dir = dir;
  options.load_stored_parameters = false;
  mdp::Device device(mdp::default_rack(), options);
  // The mailbox serves SDOs from PREOP on (ETG.1000.6 §5.3): the ESM's side tells the device.
  device.state_changed(EsmState::Init, EsmState::PreOp);
  // CoE header (SDO request), upload initiate 0x40 of 0x1018:02: the mailbox data the
  // firmware's MailboxServer hands the device's CoE.
  const std::array<uint8_t, 10> request{0x00, 0x20, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0};
  std::array<uint8_t, 250> reply{};
  const size_t n = device.coe_request(request, reply).length;
  std::filesystem::remove_all(dir);
  if (n < 10 || reply[2] != 0x43 || reply[3] != 0x18 || reply[4] != 0x10 || reply[5] != 0x02 ||
      (reply[6] | reply[7] | reply[8] | reply[9]) == 0) {
    std::fprintf(stderr, "coe_mdp: unexpected SDO reply (%zu bytes):", n);
    for (size_t i = 0; i < n && i < 32; ++i) std::fprintf(stderr, " %02x", reply[i]);
    std::fprintf(stderr, "\n");
    return 1;
  }
  std::printf("coe_mdp: 0x1018:02 product code = 0x%02x%02x%02x%02x\n", reply[9], reply[8],
              reply[7], reply[6]);
  return 0;
}
