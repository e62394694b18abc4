// Common Device Profile objects (ETG.5003.1; guide Appendix A): input latch timestamps
// 0xF6F0/0xF6F2 (per module) and the device information objects 0xF9F0..0xF9F8. Live values
// (time since power on, latch times) are filled in by mdp::Device.
#include <algorithm>
#include <chrono>

#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;

Object per_module(uint16_t index, const std::string& name, size_t modules, DataType type,
                  uint16_t access, uint64_t def) {
  Object o(index, ObjectCode::Array, name, static_cast<uint16_t>(type));
  o.add(sub0(static_cast<uint8_t>(modules)));
  for (size_t n = 1; n <= modules; ++n) {
    o.add(num(static_cast<uint8_t>(n), "Module " + std::to_string(n), type, access, def));
  }
  o.finalize();
  return o;
}

}  // namespace

void add_cdp_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  const size_t n = cfg.modules.size();
  od.add(per_module(0xF6F0, "Input Latch Local Timestamp", n, DataType::Unsigned32, acc("ro") | kTx,
                    0));
  od.add(per_module(0xF6F2, "Input Latch ESC Timestamp (64-bit)", n, DataType::Unsigned64,
                    acc("ro") | kTx, 0));
  // STRING(16) in the guide cannot hold its own serial format "<CC-CCCCCC-CC>-NNNN" (17
  // characters): the string is as long as 0x2000:03 (24).
  const std::string& serial = cfg.control.serial_number;
  od.add(var(0xF9F0, "Manufacturer Serial Number",
             str(0, "Manufacturer Serial Number",
                 static_cast<uint16_t>(std::max<size_t>(24, serial.size())), acc("ro"), serial)));
  Object cdp(0xF9F1, ObjectCode::Array, "CDP Functional Generation Number",
             static_cast<uint16_t>(DataType::Unsigned32));
  cdp.add(sub0(1));
  cdp.add(num(1, "CDP Functional Generation Number", DataType::Unsigned32, acc("ro"), 0x02));
  od.add(std::move(cdp));
  od.add(per_module(0xF9F2, "SDP Functional Generation Number", n, DataType::Unsigned32, acc("ro"),
                    0x01));
  od.add(var(0xF9F3, "Vendor Name", str(0, "Vendor Name", 16, acc("ro"), cfg.control.vendor_name)));
  // Guide default 0x412F4E: the bytes "N/A".
  od.add(per_module(0xF9F4, "Semiconductor SDP Device Name", n, DataType::Unsigned32, acc("ro"),
                    0x00412F4E));
  od.add(per_module(0xF9F5, "Output Identifier", n, DataType::Unsigned8, acc("rw") | kRx | kTx, 0));
  od.add(var(0xF9F6, "Time since power on",
             num(0, "Time since power on", DataType::Unsigned32, acc("ro"))));
  od.add(var(0xF9F8, "Firmware Update Functional Generation Number",
             num(0, "Firmware Update Functional Generation Number", DataType::Unsigned32, acc("ro"),
                 0x01)));
}

void attach_cdp_behaviour(coe::ObjectDictionary& od, DeviceRuntime& device) {
  // 0xF9F6 Time since power on, in seconds.
  od.find(0xF9F6)->edit_hooks().before_read = [&device](Object& obj, int) {
    obj.set_u(0,
              static_cast<uint32_t>(std::chrono::duration_cast<std::chrono::seconds>(
                                        std::chrono::steady_clock::now() - device.power_on_time())
                                        .count()));
  };
}

}  // namespace rackcat::mdp
