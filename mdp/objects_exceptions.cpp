// The exception tree (guide §3, Appendix A; ETG.5003.1 exception objects): active 0xF38x,
// latched 0xF39x, masks 0xF3Ax. x = 0 summary, 1 device warning details, 2 manufacturer warning
// details, 3 device error details, 4 manufacturer error details (per module: subindex n is
// module n), 6 global manufacturer warning details, 8 global manufacturer error details (one
// subindex: bit 0 device, bit rr RIM rr).
//
// The guide's tables 19/20 call the global objects 0xF385/0xF395/0xF3A5 while their headings and
// Appendix A say 0xF3x6/0xF3x8; ETG.5003.1 assigns x6/x8 to the global manufacturer details, so
// 0xF386/0xF388 it is. 0xF3x5/0xF3x7 (global device details) are not implemented, as §3.4 says,
// and Appendix A lists no 0xF3A0. Values are maintained by modules/ (propagation, guide §3);
// 0xFBF1 clears the latched objects (clear_latched_exceptions below).
#include "mdp/card_catalogue.hpp"
#include "mdp/object_dictionary_builder.hpp"
#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {
namespace {

using namespace detail;

Object per_module(uint16_t index, const char* name, size_t modules, uint16_t access, uint32_t def) {
  Object o(index, ObjectCode::Array, name, static_cast<uint16_t>(DataType::Unsigned32));
  o.add(sub0(static_cast<uint8_t>(modules)));
  for (size_t n = 1; n <= modules; ++n) {
    o.add(num(static_cast<uint8_t>(n), "Module " + std::to_string(n), DataType::Unsigned32, access,
              def));
  }
  o.finalize();
  return o;
}

Object global(uint16_t index, const char* name, uint16_t access, uint32_t def) {
  Object o(index, ObjectCode::Array, name, static_cast<uint16_t>(DataType::Unsigned32));
  o.add(sub0(1));
  o.add(num(1, name, DataType::Unsigned32, access, def));
  o.finalize();
  return o;
}

}  // namespace

void add_exception_objects(const RackConfig& cfg, coe::ObjectDictionary& od) {
  const size_t n = cfg.modules.size();
  const uint16_t status = acc("ro") | kTx;
  const uint16_t mask = acc("rw");
  od.add(var(0xF380, "Active Exception Status",
             num(0, "Active Exception Status", DataType::Unsigned8, status)));
  od.add(per_module(0xF381, "Active Device Warning Details", n, status, 0));
  od.add(per_module(0xF382, "Active Manufacturer Warning Details", n, status, 0));
  od.add(per_module(0xF383, "Active Device Error Details", n, status, 0));
  od.add(per_module(0xF384, "Active Manufacturer Error Details", n, status, 0));
  od.add(global(0xF386, "Active Global Manufacturer Warning Details", status, 0));
  od.add(global(0xF388, "Active Global Manufacturer Error Details", status, 0));
  od.add(var(0xF390, "Latched Exception Status",
             num(0, "Latched Exception Status", DataType::Unsigned8, status)));
  od.add(per_module(0xF391, "Latched Device Warning Details", n, status, 0));
  od.add(per_module(0xF392, "Latched Manufacturer Warning Details", n, status, 0));
  od.add(per_module(0xF393, "Latched Device Error Details", n, status, 0));
  od.add(per_module(0xF394, "Latched Manufacturer Error Details", n, status, 0));
  od.add(global(0xF396, "Latched Global Manufacturer Warning Details", status, 0));
  od.add(global(0xF398, "Latched Global Manufacturer Error Details", status, 0));
  // Masks: "Default of all bits TRUE (no masking)".
  od.add(per_module(0xF3A1, "Device Exception Warning Mask", n, mask, 0xFFFFFFFF));
  od.add(per_module(0xF3A2, "Manufacturer Warning Mask", n, mask, 0xFFFFFFFF));
  od.add(per_module(0xF3A3, "Device Error Mask", n, mask, 0xFFFFFFFF));
  od.add(per_module(0xF3A4, "Manufacturer Error Mask", n, mask, 0xFFFFFFFF));
  od.add(global(0xF3A6, "Global Manufacturer Warning Mask", mask, 0xFFFFFFFF));
  od.add(global(0xF3A8, "Global Manufacturer Error Mask", mask, 0xFFFFFFFF));
}

void clear_latched_exceptions(const RackConfig& config, coe::ObjectDictionary& od) {
  for (uint16_t index : {0xF390, 0xF391, 0xF392, 0xF393, 0xF394, 0xF396, 0xF398}) {
    if (Object* o = od.find(index)) {
      for (const auto& e : o->entries()) {
        if (e.subindex > 0 || o->code() == coe::ObjectCode::Var) o->set_u(e.subindex, 0);
      }
    }
  }
  // 0x2rr1:08 bits 31..2 are latched, bits 1..0 the live RIM state (guide §3.3).
  for (const auto& r : config.rims) {
    if (Object* o = od.find(rim_info_index(r.number))) o->set_u(0x08, o->get_u(0x08) & 0x3);
  }
}

}  // namespace rackcat::mdp
