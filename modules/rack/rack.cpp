#include "modules/rack/rack.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "base/event_log.hpp"
#include "base/round_time.hpp"

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "mdp/file_root.hpp"
#include "mdp/sync_manager_layout.hpp"
#include "modules/cards/encoder_driver.hpp"
#include "modules/cards/uart_driver.hpp"
#include "modules/signals/state_space_plant.hpp"

namespace rackcat::modules {
namespace {

void set_real(coe::Object* o, uint8_t sub, double v) {
  if (o != nullptr && o->entry(sub) != nullptr)
    o->set_u(sub, std::bit_cast<uint32_t>(static_cast<float>(v)));
}

bool parse_u8(std::string_view s, uint8_t& out) {
  unsigned v = 0;
  if (s.empty() || s.size() > 3) return false;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<unsigned>(c - '0');
  }
  if (v > 255) return false;
  out = static_cast<uint8_t>(v);
  return true;
}

}  // namespace

Rack::Rack(mdp::Device& device, RackOptions options)
    : options_(std::move(options)),
      device_(device),
      // ExceptionTree is the MDP exception tree (the guide's diagnosis objects), not a C++
      // exception: bugprone-throw-keyword-missing goes by the type's name alone.
      // NOLINTNEXTLINE(bugprone-throw-keyword-missing)
      tree_(device.dictionary(), device.modules().size(),
            EmergencySink{[this](uint16_t code, uint8_t reg, const uint8_t (&data)[5]) {
              device_.raise_emergency(code, reg, {data[0], data[1], data[2], data[3], data[4]});
            }}),
      cpu_fan_rpm_(options_.fan_nominal_rpm),
      cpu_temp_(options_.cpu_temperature_c) {
  start_ = base::RoundTime::now();
  if (!(options_.cycle_time_s > 0.0)) throw std::invalid_argument("cycle time must be > 0");
  const mdp::RackConfig& cfg = device_.config();
  coe::ObjectDictionary& od = device_.dictionary();

  for (const mdp::Rim& r : cfg.rims) {
    RimStatus s;
    s.number = r.number;
    s.power_supply_fan = r.power_supply_fan;
    s.slot_card_fan = r.slot_card_fan;
    s.power_supply_rpm = r.power_supply_fan ? options_.fan_nominal_rpm : 0.0;
    s.slot_card_rpm = r.slot_card_fan ? options_.fan_nominal_rpm : 0.0;
    rims_[r.number] = s;
  }
  const auto modules = device_.modules();
  drivers_.resize(modules.size());
  cycle_.resize(modules.size());
  module_rim_.resize(modules.size());
  last_safe_.assign(modules.size(), 0);
  last_unsafe_.assign(modules.size(), 0);
  for (const mdp::Module& m : modules) {
    drivers_[m.number - 1] = make_driver(m, od);
    cycle_[m.number - 1] = {drivers_[m.number - 1].get(), rims_[m.rim].state == RimState::Online};
    module_rim_[m.number - 1] = m.rim;
    rims_[m.rim].modules.push_back(m.number);
    if (auto* u = dynamic_cast<UartDriver*>(drivers_[m.number - 1].get())) uarts_.push_back(u);
    if (auto* e = dynamic_cast<EncoderDriver*>(drivers_[m.number - 1].get())) e->attach(device_);
    if (drivers_[m.number - 1]->detects_wiring_faults()) fault_drivers_.push_back(m.number - 1);
  }
  uart_cards_ = !uarts_.empty();
  channel_diag_.emplace(device_, drivers_);

  // A replay file is read below the rack file's own directory (mdp::FileRoot: no "..", no
  // absolute path, no symlink out of it), with the rights of the (unprivileged) process.
  if (!options_.files && std::filesystem::is_regular_file(cfg.source)) {
    try {
      options_.files =
          mdp::FileRoot::open(std::filesystem::path(cfg.source).parent_path().string().empty()
                                  ? std::string(".")
                                  : std::filesystem::path(cfg.source).parent_path().string());
    } catch (const std::runtime_error& e) {
      throw mdp::ConfigError(cfg.source, 0, e.what());
    }
  }
  // Channel sources and card options of the rack file (after every driver exists, so
  // loopbacks can point anywhere).
  for (const mdp::Module& m : modules) {
    const mdp::SlotCard& sc = cfg.slot_card(m);
    CardDriver& d = *drivers_[m.number - 1];
    for (const auto& [key, value] : sc.options) {
      if (key == "oversampling") continue;  // selects the catalogue variant (mdp)
      char* end = nullptr;
      const double v = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0' || !d.set_parameter(key, v)) {
        throw mdp::ConfigError(cfg.source, sc.line,
                               fmt::format("slot {}: card {} has no option '{}' (or '{}' is not "
                                           "a number)",
                                           sc.slot, m.card->name, key, value));
      }
    }
    for (const mdp::ChannelOptions& ch : sc.channels) {
      try {
        SourceParams params = ch.params;
        if (ch.loopback) {
          params["rim"] = std::to_string(ch.loopback->rim);
          params["slot"] = std::to_string(ch.loopback->slot);
          params["channel"] = std::to_string(ch.loopback->channel);
        }
        if (!ch.source.empty()) {
          set_source(m.number, ch.channel, ch.source, params);
        } else {
          if (ch.channel >= d.inputs().size())
            throw std::invalid_argument(
                fmt::format("{} has {} input channels", m.card->name, d.inputs().size()));
          for (const auto& [k, v] : params) {
            if (!is_channel_option_key(k))
              throw std::invalid_argument(fmt::format("unknown channel option '{}'", k));
          }
          set_source(m.number, ch.channel, "constant", params);
        }
      } catch (const std::invalid_argument& e) {
        throw mdp::ConfigError(
            cfg.source, ch.line,
            fmt::format("RIM {} slot {} channel {}: {}", m.rim, m.slot, ch.channel, e.what()));
      } catch (const std::runtime_error& e) {
        if (dynamic_cast<const mdp::ConfigError*>(&e)) throw;
        throw mdp::ConfigError(
            cfg.source, ch.line,
            fmt::format("RIM {} slot {} channel {}: {}", m.rim, m.slot, ch.channel, e.what()));
      }
    }
  }

  // A mask write re-evaluates the whole tree at once (guide §3.4: 0xF3A1..0xF3A8 select what
  // 0xF380 summarises; the event masks 0x2000:09 / 0x2rr1:07 what 0xF386/0xF388 count).
  auto remask = [this](coe::Object* o) {
    if (o == nullptr) return;
    auto previous = o->hooks().after_write;
    o->edit_hooks().after_write = [this, previous](coe::Object& obj, int sub) {
      if (previous) previous(obj, sub);
      tree_.update();
      dirty_ = false;
    };
  };
  for (uint16_t index = 0xF3A1; index <= 0xF3A8; ++index) remask(od.find(index));
  remask(od.find(0x2000));
  for (const mdp::Rim& r : cfg.rims) remask(od.find(mdp::rim_info_index(r.number)));

  t0_ = last_t_ = plant_t_ = now();
  publish_fans();
  publish_cpu_temperature();
  evaluate_faults();
  tree_.update();
  dirty_ = false;
  device_.add_listener(this);
}

Rack::~Rack() {
  device_.remove_listener(this);
  for (UartDriver* u : uarts_) u->stop_ptys();
}

double Rack::now() const {
  if (options_.clock) return options_.clock();
  return std::chrono::duration<double>(base::RoundTime::now() - start_).count();
}

CardDriver* Rack::driver(uint16_t module_number) {
  device_.disturb();
  if (module_number == 0 || module_number > drivers_.size()) return nullptr;
  return drivers_[module_number - 1].get();
}

CardDriver* Rack::driver_at(uint8_t rim, uint8_t slot) {
  const mdp::Module* m = device_.config().module_at(rim, slot);
  return m ? driver(m->number) : nullptr;
}

void Rack::start_uart_ptys() {
  for (UartDriver* u : uarts_) {
    u->start_ptys();
    for (size_t c = 0; c < 4; ++c) {
      spdlog::info("UART module {} (RIM {} slot {}) channel {}: {}", u->module().number,
                   u->module().rim, u->module().slot, c, u->channel(c).path);
    }
  }
}

// ---- cyclic path ---------------------------------------------------------------------------

void Rack::on_outputs(mdp::Device&) {
  // Outputs are driven only in OP; the first OP data after start (or after leaving OP) is the
  // first valid output data (power-on rule).
  if (state_ != EsmState::Op) return;
  for (const CycleCard& c : cycle_) {
    if (c.rim_online) c.driver->read_outputs();
  }
  outputs_valid_ = true;
}

void Rack::before_inputs(mdp::Device&) {
  const double t = now();
  double dt = t - last_t_;
  if (!(dt > 0.0) || dt > 1.0) dt = options_.cycle_time_s;
  last_t_ = t;
  if (!plants_.empty()) {
    int steps = 0;
    while (plant_t_ + options_.cycle_time_s <= t) {
      for (auto& [name, p] : plants_) p->step();
      plant_t_ += options_.cycle_time_s;
      if (++steps >= 10000) {  // far behind (debugger, suspend): resynchronise
        plant_t_ = t;
        break;
      }
    }
  }
  for (size_t i = 0; i < cycle_.size(); ++i) update_inputs(i, t - t0_, dt);
  evaluate_faults();
  channel_diag_->evaluate([this](size_t i) { return module_online(i); });
  if (t >= cpu_next_publish_) publish_cpu_temperature();
  const bool tree_changed = dirty_;
  if (dirty_) {
    tree_.update();
    dirty_ = false;
  }
  // Whether the next cycle with the same outputs would do all of this again to the same end
  // (mdp/repeated_cycles.hpp): no exception changed now, no plant steps with time, no UART
  // queue fills from its terminal; the cards are asked in repeats_cycle(), only when the
  // device could repeat. Control commands and RIM links call device_.disturb() first.
  settled_ = !tree_changed && state_ == EsmState::Op && plants_.empty() && !uart_cards_;
  cards_checked_ = false;
}

bool Rack::repeats_cycle() const {
  if (!settled_) return false;
  // Every card follows only the outputs and constant or looped-back sources; asked once per
  // full cycle (a source changes only through set_source, which disturbs the device).
  if (!cards_checked_) {
    cards_invariant_ = std::all_of(cycle_.begin(), cycle_.end(),
                                   [](const CycleCard& c) { return c.driver->time_invariant(); });
    cards_checked_ = true;
  }
  // The 30 s CPU temperature reading (guide §4.8) is the rack's own timer.
  return cards_invariant_ && now() < cpu_next_publish_;
}

void Rack::on_clock() {
  device_.disturb();
  if (now() >= cpu_next_publish_) publish_cpu_temperature();
  if (dirty_) {
    tree_.update();
    dirty_ = false;
  }
}

void Rack::evaluate_faults() {
  bool unsafe_in_rim[6] = {};
  bool any_unsafe = false;
  for (const uint16_t i : fault_drivers_) {
    CardDriver& d = *drivers_[i];
    const uint32_t safe = d.safe_wiring_faults();
    const uint32_t unsafe = d.unsafe_wiring_faults();
    if (unsafe) {
      unsafe_in_rim[module_rim_[i]] = true;
      any_unsafe = true;
    }
    if (safe != last_safe_[i] || unsafe != last_unsafe_[i]) {
      last_safe_[i] = safe;
      last_unsafe_[i] = unsafe;
      tree_.set_module_faults(static_cast<uint16_t>(i + 1), safe, unsafe);
      dirty_ = true;
    }
  }
  // An unsafe wiring fault takes its RIM out of ONLINE (guide Table 23): the RIM drives its
  // outputs to the TÜV-safe level; it returns when the fault is gone. An ERROR state set for
  // another reason (guide Table 16 state 3, `rackcat ctl rim-state`) is not the fault's to end.
  // Nothing to do while no RIM has an unsafe fault and none ever went to ERROR for one.
  if (!any_unsafe && !fault_error_seen_) return;
  for (auto& [rr, rim] : rims_) {
    if (unsafe_in_rim[rr] && rim.state == RimState::Online) {
      set_rim_state(rr, RimState::Error, rim.comm_error);
      rim.fault_error = true;
      fault_error_seen_ = true;
    } else if (!unsafe_in_rim[rr] && rim.state == RimState::Error && rim.fault_error) {
      set_rim_state(rr, RimState::Online, false);
    }
  }
}

void Rack::on_state_changed(mdp::Device&, EsmState from, EsmState to) {
  state_ = to;
  if (from == EsmState::Op && to != EsmState::Op) {
    apply_safe_states();
    outputs_valid_ = false;
  }
}

void Rack::apply_safe_states() {
  for (size_t i = 0; i < drivers_.size(); ++i) {
    if (module_online(i)) drivers_[i]->apply_safe_state();
  }
  dirty_ = true;
}

void Rack::on_watchdog_expired(mdp::Device&) {
  if (state_ == EsmState::Op) apply_safe_states();
  outputs_valid_ = false;
  device_.raise_emergency(emcy::kPdTimeout, emcy::kRegGeneric | emcy::kRegCommunication, {});
}

void Rack::on_exception_reset(mdp::Device&) {
  tree_.reset_latched();
  channel_diag_->reset();  // the history is empty again: active channel causes re-appear
  dirty_ = false;
}

void Rack::on_detect_modules(mdp::Device& device) {
  // Guide Table 23: with Detect Modules Override 0 the command enumerates only the cards it
  // detects now, so the cards of a RIM that is not online leave 0xF050 (mdp filled it with
  // the whole rack; ETG.5001.1: the detected list holds the modules present, in order).
  // The device makes 0x3000, 0xF030 and 0x1C12/0x1C13 follow (mdp/module_enumeration.hpp).
  enumerate(device);
  refresh();
}

void Rack::enumerate(mdp::Device& device) {
  device_.disturb();
  const auto modules = device.modules();
  std::vector<uint8_t> present(modules.size(), 1);
  if (!detect_modules_override()) {
    for (size_t i = 0; i < modules.size(); ++i) present[i] = module_online(i) ? 1 : 0;
  }
  device.enumerate_modules(present);
}

void Rack::on_device_reset(mdp::Device& device, bool) {
  // 0xFBF0 emulates a power cycle: outputs undriven until new valid data, latched exceptions
  // gone (the physical causes - unplugged RIMs, faults, fans - stay as they are); the modules
  // are enumerated as at system initialization (guide Table 23).
  enumerate(device);
  for (size_t i = 0; i < drivers_.size(); ++i) drivers_[i]->de_energise();
  outputs_valid_ = false;
  publish_cpu_temperature();
  tree_.reset_latched();
  dirty_ = false;
}

void Rack::on_parameters_loaded(mdp::Device&) {
  for (UartDriver* u : uarts_) u->reload_config();
  refresh();
}

// ---- state and fault injection ------------------------------------------------------------

uint16_t Rack::check_state_request(EsmState from, EsmState to) const {
  if (to != EsmState::Op || from == EsmState::Op) return 0;
  if (detect_modules_override()) return 0;
  for (const auto& [rr, rim] : rims_) {
    if (rim.state != RimState::Online && rim_has_mapped_process_data(rr))
      return kAlStatusModuleMissing;
  }
  return 0;
}

bool Rack::detect_modules_override() const {
  const coe::Object* o = device_.dictionary().find(0x2000);
  if (o == nullptr || o->entry(0x0B) == nullptr) return device_.config().detect_modules_override;
  return o->get_u(0x0B) != 0;
}

bool Rack::rim_has_mapped_process_data(uint8_t rim) const {
  const coe::ObjectDictionary& od = device_.dictionary();
  struct Assign {
    uint16_t index, base;
  };
  for (const Assign a :
       {Assign{0x1C12, mdp::sm::kRxPdoBase}, Assign{0x1C13, mdp::sm::kTxPdoBase}}) {
    const coe::Object* o = od.find(a.index);
    if (o == nullptr) continue;
    for (uint8_t k = 1; k <= o->sub0(); ++k) {
      const auto pdo = static_cast<uint16_t>(o->get_u(k));
      if (pdo < a.base) continue;
      const size_t module = static_cast<size_t>(pdo - a.base) / mdp::sm::kPdoIndexIncrement + 1;
      if (module <= module_rim_.size() && module_rim_[module - 1] == rim) return true;
    }
  }
  return false;
}

namespace {
// An injected fault for the log (base/event_log.hpp); nothing is formatted here.
void log_fault(base::FaultWhat what, uint16_t module, size_t channel_or_rim, uint32_t value,
               std::string_view text = {}) {
  base::Event e{.kind = base::EventKind::FaultInjected,
                .a = static_cast<uint8_t>(channel_or_rim),
                .b = static_cast<uint8_t>(what),
                .index = module,
                .value = value};
  e.set_text(text);
  base::log_event(e);
}
}  // namespace

void Rack::set_rim_state(uint8_t rr, RimState state, bool comm_error) {
  device_.disturb();
  auto it = rims_.find(rr);
  if (it == rims_.end()) throw std::invalid_argument(fmt::format("there is no RIM {}", rr));
  RimStatus& rim = it->second;
  const RimState prev = rim.state;
  rim.state = state;
  if (prev != state) {
    base::log_event({.kind = base::EventKind::RimState,
                     .a = rr,
                     .b = static_cast<uint8_t>(prev),
                     .c = static_cast<uint8_t>(state),
                     .code = comm_error ? uint16_t{1} : uint16_t{0}});
  }
  rim.comm_error = comm_error;
  rim.fault_error = false;
  tree_.set_rim_state(rr, state, comm_error);
  for (uint16_t n : rim.modules) {
    cycle_[n - 1].rim_online = state == RimState::Online;
    CardDriver& d = *drivers_[n - 1];
    if (state != RimState::Online) {
      // The RIM drives its outputs to the TÜV-safe level; its inputs are gone.
      d.de_energise();
      d.clear_inputs();
      d.substitute_inputs(true);
    } else if (prev != RimState::Online && state_ == EsmState::Op && outputs_valid_) {
      d.read_outputs();
    }
  }
  tree_.update();
  dirty_ = false;
  if (prev == RimState::Online && state != RimState::Online && state_ == EsmState::Op &&
      !detect_modules_override() && rim_has_mapped_process_data(rr) && state_request_) {
    // Guide Table 23, Detect Modules Override 0: OP -> SAFEOP, outputs to their safe states.
    state_request_(EsmState::SafeOp, kAlStatusModuleMissing);
  }
}

void Rack::set_fan_rpm(uint8_t rr, std::string_view zone, double rpm) {
  device_.disturb();
  if (!std::isfinite(rpm) || rpm < 0.0 || rpm > 100000.0)
    throw std::invalid_argument("rpm must be 0..100000");
  if (rr == 0) {
    if (!zone.empty() && zone != "cpu")
      throw std::invalid_argument("the control module has only the 'cpu' fan zone");
    cpu_fan_rpm_ = rpm;
  } else {
    auto it = rims_.find(rr);
    if (it == rims_.end()) throw std::invalid_argument(fmt::format("there is no RIM {}", rr));
    RimStatus& rim = it->second;
    if (zone == "power_supply") {
      if (!rim.power_supply_fan)
        throw std::invalid_argument(fmt::format("RIM {} has no power-supply fan", rr));
      rim.power_supply_rpm = rpm;
    } else if (zone == "slot_card") {
      if (!rim.slot_card_fan)
        throw std::invalid_argument(fmt::format("RIM {} has no slot-card fan", rr));
      rim.slot_card_rpm = rpm;
    } else {
      throw std::invalid_argument("fan zone must be 'power_supply' or 'slot_card'");
    }
  }
  publish_fans();
  tree_.update();
  dirty_ = false;
  log_fault(base::FaultWhat::FanRpm, 0, rr, static_cast<uint32_t>(rpm));
}

void Rack::set_rim_mcm_errors(uint8_t rr, uint32_t bits) {
  device_.disturb();
  auto it = rims_.find(rr);
  if (it == rims_.end()) throw std::invalid_argument(fmt::format("there is no RIM {}", rr));
  constexpr uint32_t kMcm = rim_event::kSlotMachineMcm0 | rim_event::kSoutCompareMcm0 |
                            rim_event::kSlotMachineMcm1 | rim_event::kSoutCompareMcm1;
  if (bits & ~kMcm) throw std::invalid_argument("MCM error bits are 16..19 of 0x2rr1:08");
  it->second.mcm_errors = bits;
  publish_fans();
  tree_.update();
  dirty_ = false;
  log_fault(base::FaultWhat::McmErrors, 0, rr, bits);
}

void Rack::publish_fans() {
  coe::ObjectDictionary& od = device_.dictionary();
  const double nominal = options_.fan_nominal_rpm;
  auto deviation = [nominal](double rpm) { return (rpm / nominal - 1.0) * 100.0; };
  coe::Object* dev = od.find(0x2000);
  set_real(dev, 0x0D, deviation(cpu_fan_rpm_));
  set_real(dev, 0x0E, cpu_fan_rpm_);
  tree_.set_device_events(fan_level_bits(deviation(cpu_fan_rpm_)) << 8);  // Table 15 bits 8-10
  for (const auto& [rr, rim] : rims_) {
    coe::Object* info = od.find(mdp::rim_info_index(rr));
    // Guide Table 2: a missing fan reads -100 (deviation) and 0 (RPM).
    const double ps_dev = rim.power_supply_fan ? deviation(rim.power_supply_rpm) : -100.0;
    const double slot_dev = rim.slot_card_fan ? deviation(rim.slot_card_rpm) : -100.0;
    set_real(info, 0x0A, ps_dev);
    set_real(info, 0x0B, slot_dev);
    set_real(info, 0x0C, rim.power_supply_fan ? rim.power_supply_rpm : 0.0);
    set_real(info, 0x0D, rim.slot_card_fan ? rim.slot_card_rpm : 0.0);
    uint32_t events = 0;
    if (rim.slot_card_fan) events |= fan_level_bits(slot_dev) << 8;    // Table 16 8-10
    if (rim.power_supply_fan) events |= fan_level_bits(ps_dev) << 12;  // 12-14
    events |= rim.mcm_errors;
    tree_.set_rim_events(rr, events);
  }
  dirty_ = true;
}

void Rack::set_cpu_temperature(double celsius, bool publish_now) {
  device_.disturb();
  if (!std::isfinite(celsius) || celsius < -55.0 || celsius > 150.0)
    throw std::invalid_argument("CPU temperature must be -55..150 degC");
  cpu_temp_ = celsius;
  if (publish_now) publish_cpu_temperature();
  log_fault(base::FaultWhat::CpuTemperature, 0, 0,
            static_cast<uint32_t>(static_cast<int32_t>(std::lround(celsius * 10.0))));
}

void Rack::publish_cpu_temperature() {
  // Guide §4.8: 0.5 °C resolution, a new reading every 30 s.
  const double q = std::round(cpu_temp_ * 2.0) / 2.0;
  cpu_temp_published_ = q;
  set_real(device_.dictionary().find(0x2000), 0x0F, q);
  cpu_next_publish_ = now() + options_.cpu_temperature_period_s;
  const uint8_t data[5] = {0, 0, 0xFF, 0, 0};
  if (q >= options_.cpu_temperature_limit_c && !over_temperature_) {
    over_temperature_ = true;
    device_.raise_emergency(emcy::kOverTemperature, emcy::kRegGeneric | emcy::kRegTemperature,
                            {data[0], data[1], data[2], data[3], data[4]});
  } else if (q < options_.cpu_temperature_limit_c - 2.0 && over_temperature_) {
    // 2 °C hysteresis so a reading at the limit does not flood the mailbox.
    over_temperature_ = false;
    device_.raise_emergency(emcy::kNoError, 0, {data[0], data[1], data[2], data[3], data[4]});
  }
}

void Rack::set_wiring_fault(uint16_t module, size_t channel, WiringFault fault) {
  device_.disturb();
  CardDriver* d = driver(module);
  if (d == nullptr) throw std::invalid_argument(fmt::format("there is no module {}", module));
  if (!d->detects_wiring_faults())
    throw std::invalid_argument(fmt::format(
        "module {} ({}) cannot detect wiring faults: only sourcing digital outputs can (guide "
        "4.7)",
        module, d->card().name));
  if (channel >= d->outputs().size())
    throw std::invalid_argument(
        fmt::format("module {} has {} output channels", module, d->outputs().size()));
  d->set_wiring_fault(channel, fault);
  log_fault(base::FaultWhat::WiringFault, module, channel, static_cast<uint32_t>(fault));
  evaluate_faults();
  tree_.update();
  dirty_ = false;
}

void Rack::set_sensor_open(uint16_t module, size_t channel, bool open) {
  device_.disturb();
  CardDriver* d = driver(module);
  if (d == nullptr) throw std::invalid_argument(fmt::format("there is no module {}", module));
  if (!d->has_sensor_break())
    throw std::invalid_argument(
        fmt::format("module {} ({}) is not a thermocouple or RTD card", module, d->card().name));
  if (channel >= d->inputs().size())
    throw std::invalid_argument(
        fmt::format("module {} has {} input channels", module, d->inputs().size()));
  d->inputs()[channel].open = open;
  log_fault(base::FaultWhat::SensorOpen, module, channel, open ? 1 : 0);
}

void Rack::set_output_fault(uint16_t module, size_t channel, bool overload, bool overtemperature) {
  device_.disturb();
  CardDriver* d = driver(module);
  if (d == nullptr) throw std::invalid_argument(fmt::format("there is no module {}", module));
  if (channel >= d->outputs().size())
    throw std::invalid_argument(
        fmt::format("module {} has {} output channels", module, d->outputs().size()));
  d->outputs()[channel].overload = overload;
  d->outputs()[channel].overtemperature = overtemperature;
  channel_diag_->watch_outputs(module - 1u);
}

void Rack::set_encoder_fault(uint16_t module, EncoderFault fault, bool active, int64_t jump_steps) {
  device_.disturb();
  auto* e = dynamic_cast<EncoderDriver*>(driver(module));
  if (e == nullptr) {
    throw std::invalid_argument(fmt::format("module {} is not an encoder card", module));
  }
  e->set_fault(fault, active, jump_steps);
}

void Rack::set_loop_ohms(uint16_t module, size_t channel, double ohms) {
  device_.disturb();
  CardDriver* d = driver(module);
  if (d == nullptr) throw std::invalid_argument(fmt::format("there is no module {}", module));
  if (!d->card().thermocouple_ohms)
    throw std::invalid_argument(
        fmt::format("module {} ({}) has no loop resistance (0x5nn4)", module, d->card().name));
  if (channel >= d->inputs().size())
    throw std::invalid_argument(
        fmt::format("module {} has {} input channels", module, d->inputs().size()));
  if (!std::isfinite(ohms) || ohms < 0.0 || ohms > 65534.0)
    throw std::invalid_argument("loop_ohms must be 0..65534");
  d->inputs()[channel].loop_ohms = ohms;
  log_fault(base::FaultWhat::LoopOhms, module, channel, static_cast<uint32_t>(ohms));
}

void Rack::set_source(uint16_t module, size_t channel, std::string_view kind,
                      const SourceParams& params, std::unique_ptr<Source> prebuilt) {
  device_.disturb();
  CardDriver* d = driver(module);
  if (d == nullptr) throw std::invalid_argument(fmt::format("there is no module {}", module));
  if (channel >= d->inputs().size()) {
    throw std::invalid_argument(fmt::format("module {} ({}) has {} input channels", module,
                                            d->card().name, d->inputs().size()));
  }
  // Validate everything before changing anything.
  std::optional<double> ohms;
  std::optional<bool> open;
  if (auto it = params.find("loop_ohms"); it != params.end()) {
    char* end = nullptr;
    ohms = std::strtod(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0')
      throw std::invalid_argument("loop_ohms is not a number");
    if (!d->card().thermocouple_ohms) throw std::invalid_argument("loop_ohms: not a thermocouple");
  }
  if (auto it = params.find("open"); it != params.end()) {
    if (it->second != "true" && it->second != "false")
      throw std::invalid_argument("open must be true or false");
    open = it->second == "true";
    if (!d->has_sensor_break()) throw std::invalid_argument("open: not a thermocouple or RTD");
  }
  if (params.count("cold_junction_c"))
    throw std::invalid_argument("cold_junction_c is a card option, not a channel option");
  std::unique_ptr<Source> s = std::move(prebuilt);
  if (!s) {
    SourceContext ctx = source_context();
    s = make_source(kind, params, ctx);
  }
  if (ohms) set_loop_ohms(module, channel, *ohms);
  if (open) d->inputs()[channel].open = *open;
  d->set_source(channel, std::move(s));
  log_fault(base::FaultWhat::Source, module, channel, 0, kind);
}

OutputRef Rack::output_ref(uint8_t rim, uint8_t slot, uint8_t channel) {
  CardDriver* d = driver_at(rim, slot);
  if (d == nullptr) return {nullptr, fmt::format("no card in RIM {} slot {}", rim, slot)};
  if (channel >= d->outputs().size()) {
    return {nullptr, fmt::format("RIM {} slot {} ({}) has no output channel {}", rim, slot,
                                 d->card().name, channel)};
  }
  return {&d->outputs()[channel].wire, fmt::format("rim{}.slot{}.out{}", rim, slot, channel)};
}

StateSpacePlant& Rack::plant(const std::string& name, const SourceParams& params) {
  auto it = plants_.find(name);
  if (it != plants_.end()) return *it->second;
  auto p = make_plant(params, options_.cycle_time_s, [this](const std::string& ref) {
    // "rim.slot.channel"
    uint8_t v[3] = {};
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
      const size_t dot = k < 2 ? ref.find('.', start) : ref.size();
      if (dot == std::string::npos ||
          !parse_u8(std::string_view(ref).substr(start, dot - start), v[k]))
        return OutputRef{nullptr, fmt::format("'{}' is not rim.slot.channel", ref)};
      start = dot + 1;
    }
    return output_ref(v[0], v[1], v[2]);
  });
  StateSpacePlant& ref = *p;
  plants_.emplace(name, std::move(p));
  return ref;
}

SourceContext Rack::source_context() {
  SourceContext ctx;
  ctx.output = [this](uint8_t rim, uint8_t slot, uint8_t ch) { return output_ref(rim, slot, ch); };
  ctx.module_position = [this](uint16_t module, uint8_t& rim, uint8_t& slot) {
    if (module == 0 || module > drivers_.size()) return false;
    rim = drivers_[module - 1]->module().rim;
    slot = drivers_[module - 1]->module().slot;
    return true;
  };
  ctx.plant = [this](const std::string& name, const SourceParams& params) -> StateSpacePlant& {
    return plant(name, params);
  };
  if (options_.files) {
    ctx.read_file = [files = options_.files](const std::string& file, size_t max_bytes) {
      return files->read(file, max_bytes);
    };
  }
  return ctx;
}

void Rack::sample_inputs(uint16_t module) {
  device_.disturb();
  CardDriver* d = driver(module);
  if (d != nullptr && module_online(module - 1u)) {
    d->write_inputs(now() - t0_, options_.cycle_time_s);
    d->substitute_inputs(false);
  }
}

void Rack::update_inputs(size_t i, double t, double dt) {
  const CycleCard& c = cycle_[i];
  CardDriver& d = *c.driver;
  if (c.rim_online) {
    d.write_inputs(t, dt);
    d.substitute_inputs(false);
  } else {
    // The source is missing: the card's own code (0), then the channel's substitute
    // (mdp/substitute_values.hpp), so a reaction written meanwhile applies at once.
    d.clear_inputs();
    d.substitute_inputs(true);
  }
}

void Rack::refresh() {
  device_.disturb();
  if (state_ != EsmState::SafeOp && state_ != EsmState::Op) {
    // No process data runs: sample the inputs here so SDO reads and `ctl list` are live.
    const double t = now();
    for (size_t i = 0; i < cycle_.size(); ++i) update_inputs(i, t - t0_, options_.cycle_time_s);
  }
  publish_fans();
  evaluate_faults();
  channel_diag_->evaluate([this](size_t i) { return module_online(i); });
  tree_.update();
  dirty_ = false;
}

}  // namespace rackcat::modules
