// ENI CoE init commands replayed through the device's SDO server (see init_cmd_replay.hpp).
#include "apps/line/init_cmd_replay.hpp"

#include <array>
#include <cstdio>

#include "base/little_endian.hpp"
#include "coe/abort_code.hpp"
#include "coe/sdo_server.hpp"
#include "device/esi_error.hpp"
#include "device/pdo_checks.hpp"

namespace rackcat::apps {
namespace {

// CoE header (ETG.1000.6 §5.6.1: number 0, service 2 = SDO request) and a download initiate
// request, normal transfer with the size indicated (§5.6.2.1.1 Table 37: command 0x21, bit 4
// complete access), the whole data in this one request.
std::vector<uint8_t> download_request(const SdoWrite& w) {
  std::vector<uint8_t> r(2 + 8 + w.data.size());
  le::put16(r.data(), 0x2000);
  r[2] = static_cast<uint8_t>(0x21 | (w.complete_access ? 0x10 : 0));
  le::put16(&r[3], w.index);
  r[5] = w.subindex;
  le::put32(&r[6], static_cast<uint32_t>(w.data.size()));
  std::copy(w.data.begin(), w.data.end(), r.begin() + 10);
  return r;
}

}  // namespace

coe::ObjectDictionary replay_sdo_writes(const device::EsiDevice& dev,
                                        const std::vector<SdoWrite>& writes,
                                        const std::string& file) {
  coe::ObjectDictionary od = dev.dictionary;
  device::install_pdo_checks(od, dev.description);
  coe::SdoServer sdo(od);
  std::array<uint8_t, 1024> reply{};
  for (const auto& w : writes) {
    const auto answer = sdo.handle(download_request(w), reply, w.state);
    char what[64];
    std::snprintf(what, sizeof what, "InitCmd writes 0x%04X:%u%s", w.index, w.subindex,
                  w.complete_access ? " (complete access)" : "");
    if (answer.error != mailbox::Error::None || answer.length < 10)
      throw device::FileError(file, w.line,
                              std::string(what) + ": the device answers no SDO download response");
    // SDO abort (§5.6.2.7): command 0x80, index, subindex, abort code.
    if (reply[2] == 0x80) {
      const auto code = static_cast<coe::AbortCode>(le::get32(&reply[6]));
      char abort[32];
      std::snprintf(abort, sizeof abort, "SDO abort 0x%08X", static_cast<uint32_t>(code));
      throw device::FileError(file, w.line,
                              std::string(what) + " but " + dev.description.order_code + " (" +
                                  dev.file + ") answers " + abort + " (" +
                                  std::string(coe::describe(code)) + ")");
    }
  }
  return od;
}

}  // namespace rackcat::apps
