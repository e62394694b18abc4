#include "modules/rim/rack_link.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "coe/bits.hpp"

namespace rackcat::modules::canopen {

void attach_rim_master(RimMaster& master, Rack& rack) {
  for (uint8_t r : master.rims()) {
    const RimProfile& p = *master.profile(r);
    for (const RimChannel& c : p.inputs) {
      CardDriver* d = rack.driver_at(r, c.slot);
      if (!d || c.channel >= d->inputs().size()) {
        throw std::invalid_argument(
            fmt::format("rack has no input channel {} in RIM {} slot {}", c.channel, r, c.slot));
      }
      d->set_source(c.channel, std::make_unique<RemoteInputSource>(
                                   master.input_ptr(r, c.slot, c.channel),
                                   fmt::format("rim{}.slot{}.in{}", r, c.slot, c.channel)));
    }
    for (const RimChannel& c : p.outputs) {
      CardDriver* d = rack.driver_at(r, c.slot);
      if (!d || c.channel >= d->outputs().size()) {
        throw std::invalid_argument(
            fmt::format("rack has no output channel {} in RIM {} slot {}", c.channel, r, c.slot));
      }
      master.bind_output(r, c.slot, c.channel, &d->outputs()[c.channel].driven);
    }
    // Until its heartbeat arrives the RIM is not there.
    rack.set_rim_state(r, master.state(r), false);
  }
  master.on_state([&rack](uint8_t rim, RimState state, bool comm_error) {
    rack.set_rim_state(rim, state, comm_error);
  });
  master.on_emergency([&rack](uint8_t rim, const coe::Emergency& e) {
    if (e.error_code == emcy::kFan) {
      const char* zone = e.data[0] == 0 ? "power_supply" : "slot_card";
      try {
        rack.set_fan_rpm(rim, zone, le::get16(&e.data[1]));
      } catch (const std::invalid_argument&) {
        // The rack file says this RIM has no such fan: nothing to show.
      }
    }
  });
}

}  // namespace rackcat::modules::canopen
