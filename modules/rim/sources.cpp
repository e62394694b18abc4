#include "modules/rim/sources.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "modules/signals/source_factory.hpp"
#include "modules/signals/state_space_plant.hpp"

namespace rackcat::modules::canopen {

void apply_rack_sources(RimNode& node, const mdp::RackConfig& rack) {
  const uint8_t rim = node.profile().rim;
  const mdp::Rim* r = rack.rim(rim);
  if (!r) return;
  SourceContext ctx;
  ctx.output = [&node, rim](uint8_t rr, uint8_t slot, uint8_t channel) {
    OutputRef ref;
    ref.name = fmt::format("rim{}.slot{}.out{}", rr, slot, channel);
    if (rr != rim) {
      ref.name = fmt::format(
          "{} is in another RIM (a separate RIM process sees only its own "
          "outputs)",
          ref.name);
      return ref;
    }
    ref.value = node.output_ptr(slot, channel);
    if (!ref.value) ref.name += " is no output channel carried on CAN";
    return ref;
  };
  ctx.module_position = [&rack](uint16_t module, uint8_t& rr, uint8_t& slot) {
    for (const mdp::Module& m : rack.modules) {
      if (m.number == module) {
        rr = m.rim;
        slot = m.slot;
        return true;
      }
    }
    return false;
  };
  ctx.plant = [](const std::string& name, const SourceParams&) -> StateSpacePlant& {
    throw std::invalid_argument("plant '" + name +
                                "' needs the whole rack: plant sources run only in `rackcat run`");
  };
  for (const mdp::SlotCard& sc : r->slots) {
    for (const mdp::ChannelOptions& ch : sc.channels) {
      try {
        SourceParams params = ch.params;
        if (auto f = params.find("file"); f != params.end() && !f->second.empty() &&
                                          f->second.front() != '/' &&
                                          std::filesystem::exists(rack.source)) {
          f->second =
              (std::filesystem::path(rack.source).parent_path() / f->second).lexically_normal();
        }
        if (ch.loopback) {
          params["rim"] = std::to_string(ch.loopback->rim);
          params["slot"] = std::to_string(ch.loopback->slot);
          params["channel"] = std::to_string(ch.loopback->channel);
        }
        // Sensor options (open circuit, loop resistance) belong to the rack's drivers.
        for (auto it = params.begin(); it != params.end();) {
          it = is_channel_option_key(it->first) ? params.erase(it) : std::next(it);
        }
        if (ch.source.empty()) continue;
        auto source = make_source(ch.source, params, ctx);
        if (!node.set_source(sc.slot, ch.channel, std::move(source))) {
          throw std::invalid_argument(
              fmt::format("card {} has no input channel {} on CAN", sc.card->name, ch.channel));
        }
      } catch (const std::invalid_argument& e) {
        throw mdp::ConfigError(
            rack.source, ch.line,
            fmt::format("RIM {} slot {} channel {}: {}", rim, sc.slot, ch.channel, e.what()));
      } catch (const std::runtime_error& e) {
        if (dynamic_cast<const mdp::ConfigError*>(&e)) throw;
        throw mdp::ConfigError(
            rack.source, ch.line,
            fmt::format("RIM {} slot {} channel {}: {}", rim, sc.slot, ch.channel, e.what()));
      }
    }
  }
}

}  // namespace rackcat::modules::canopen
