// PDO configuration checks of an ESI device (see pdo_checks.hpp).
#include "device/pdo_checks.hpp"

#include "coe/pdo_mapping.hpp"

namespace rackcat::device {

void install_pdo_checks(coe::ObjectDictionary& od, const esi::DeviceDescription& d) {
  size_t max_out = kUnboundedSmBytes, max_in = kUnboundedSmBytes;
  for (const auto& sm : d.sms) {
    if (sm.max_size == 0) continue;
    if (sm.type == esi::SmType::ProcessOut) max_out = sm.max_size;
    if (sm.type == esi::SmType::ProcessIn) max_in = sm.max_size;
  }
  coe::install_pdo_validators(od, max_out, max_in);
}

}  // namespace rackcat::device
