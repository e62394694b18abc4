#include "modules/control/live_snapshot.hpp"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "modules/rack/events.hpp"

namespace rackcat::modules {
namespace {

double finite(double v) {
  return std::isfinite(v) ? v : 0.0;
}

}  // namespace

LiveSnapshot::LiveSnapshot(const std::vector<Rack*>& racks) {
  slaves_.resize(racks.size());
  for (size_t i = 0; i < racks.size(); ++i) {
    Slave& s = slaves_[i];
    s.rack = racks[i] != nullptr;
    if (!s.rack) continue;
    for (const auto& [number, rim] : racks[i]->rims()) s.rims.push_back(Rim{number});
    for (const auto& d : racks[i]->drivers()) {
      Module m;
      m.number = d->module().number;
      m.inputs.resize(d->inputs().size());
      m.input_open.resize(d->inputs().size());
      m.commanded.resize(d->outputs().size());
      m.driven.resize(d->outputs().size());
      m.wire.resize(d->outputs().size());
      s.modules.push_back(std::move(m));
    }
  }
}

void LiveSnapshot::capture(const std::vector<Rack*>& racks, const SlaveLinkFn& link) {
  ++sequence_;
  time_s_ = 0;
  for (size_t i = 0; i < racks.size() && i < slaves_.size(); ++i) {
    Slave& s = slaves_[i];
    if (link) link(i, s.link);
    if (racks[i] == nullptr || !s.rack) continue;
    const Rack& r = *racks[i];
    if (time_s_ == 0) time_s_ = r.now();
    s.esm = r.esm_state();
    s.outputs_valid = r.outputs_valid();
    s.cpu_fan_rpm = r.cpu_fan_rpm();
    s.cpu_temperature = r.cpu_temperature();
    const ExceptionTree& t = r.exceptions();
    s.summary_active = t.summary(false);
    s.summary_latched = t.summary(true);
    s.device_event_status = t.device_event_status();
    const coe::diag::History& h = racks[i]->device().diagnosis();
    s.diagnosis_messages = static_cast<uint32_t>(h.count());
    s.diagnosis_newest = h.newest_subindex();
    size_t k = 0;
    for (const auto& [number, rim] : r.rims()) {
      if (k >= s.rims.size()) break;
      Rim& out = s.rims[k++];
      out.number = number;
      out.state = rim.state;
      out.comm_error = rim.comm_error;
      out.power_supply_rpm = rim.power_supply_rpm;
      out.slot_card_rpm = rim.slot_card_rpm;
      out.event_status = t.rim_event_status(number);
    }
    const auto drivers = r.drivers();
    for (size_t m = 0; m < drivers.size() && m < s.modules.size(); ++m) {
      Module& out = s.modules[m];
      const auto in = drivers[m]->inputs();
      for (size_t c = 0; c < in.size() && c < out.inputs.size(); ++c) {
        out.inputs[c] = in[c].value;
        out.input_open[c] = in[c].open ? 1 : 0;
      }
      const auto o = drivers[m]->outputs();
      for (size_t c = 0; c < o.size() && c < out.commanded.size(); ++c) {
        out.commanded[c] = o[c].commanded;
        out.driven[c] = o[c].driven;
        out.wire[c] = o[c].wire;
      }
    }
  }
}

std::string LiveSnapshot::to_json() const {
  using json = nlohmann::json;
  auto hex32 = [](uint32_t v) { return fmt::format("0x{:08X}", v); };
  json slaves = json::array();
  for (size_t i = 0; i < slaves_.size(); ++i) {
    const Slave& s = slaves_[i];
    const SlaveLink& l = s.link;
    json link{{"slave", i},
              {"position", l.position},
              {"rack", s.rack},
              {"station_address", l.station_address},
              {"al_status", l.al_status},
              {"al_status_code", l.al_status_code},
              {"al_status_text", l.al_status_text ? l.al_status_text : ""},
              {"pd_watchdog_running", l.pd_watchdog_running},
              {"pd_watchdog_expiries", l.pd_watchdog_expiries},
              {"rx_errors", l.rx_errors},
              {"frames", l.frames},
              {"vendor_id", fmt::format("0x{:08X}", l.vendor_id)},
              {"product_code", fmt::format("0x{:08X}", l.product_code)},
              {"revision", fmt::format("0x{:08X}", l.revision)}};
    if (!s.rack) {
      link["esm"] = esm_state_name(l.al_status);
      slaves.push_back(std::move(link));
      continue;
    }
    json rims = json::array();
    for (const Rim& r : s.rims) {
      rims.push_back({{"rim", r.number},
                      {"state", rim_state_name(r.state)},
                      {"comm_error", r.comm_error},
                      {"power_supply_rpm", finite(r.power_supply_rpm)},
                      {"slot_card_rpm", finite(r.slot_card_rpm)},
                      {"event_status", hex32(r.event_status)}});
    }
    json modules = json::array();
    for (const Module& m : s.modules) {
      json inputs = json::array();
      for (size_t c = 0; c < m.inputs.size(); ++c) {
        inputs.push_back(m.input_open[c] ? json(nullptr) : json(finite(m.inputs[c])));
      }
      json outputs = json::array();
      for (size_t c = 0; c < m.commanded.size(); ++c) {
        outputs.push_back({finite(m.commanded[c]), finite(m.driven[c]), finite(m.wire[c])});
      }
      modules.push_back(
          {{"module", m.number}, {"in", std::move(inputs)}, {"out", std::move(outputs)}});
    }
    link.update({{"esm", esm_state_name(s.esm)}, {"outputs_valid", s.outputs_valid}});
    link.update(json{{"cpu_fan_rpm", finite(s.cpu_fan_rpm)},
                     {"cpu_temperature", finite(s.cpu_temperature)},
                     {"F380", hex32(s.summary_active)},
                     {"F390", hex32(s.summary_latched)},
                     {"device_event_status", hex32(s.device_event_status)},
                     {"diagnosis_messages", s.diagnosis_messages},
                     {"diagnosis_newest", s.diagnosis_newest},
                     {"rims", std::move(rims)},
                     {"modules", std::move(modules)}});
    slaves.push_back(std::move(link));
  }
  return json{{"seq", sequence_}, {"t", time_s_}, {"slaves", std::move(slaves)}}.dump();
}

}  // namespace rackcat::modules
