// The emulated rack's behaviour behind an mdp::Device: one slot-card driver per module, the
// signal models, safe states, the RIM state machine with fans and CPU temperature, the
// exception tree with its CoE Emergencies. The fault-injection control API
// (modules/control/control_api.hpp) is a separate object its owner creates on a Rack.
//
// Use (as apps/rack_slave and apps/cmd_run.cpp do):
//
//   mdp::Device device(config);
//   modules::Rack rack(device);                         // attaches itself as CycleListener
//   rack.set_state_request_handler([&](EsmState to, uint16_t al_status) {
//     esc_loop.post([&, to, al_status] { firmware.application_error(to, al_status); });
//   });
//   // In ecat::Application::on_state_request(from, to), after device.request_state():
//   //   if (uint16_t code = rack.check_state_request(from, to)) return code;
//   rack.start_uart_ptys();                             // prints each /dev/pts/N
//
// Threading: everything runs on the thread that drives the Device (the ESC's cyclic thread).
// The control API (modules/control/control_api.hpp, owned by the application) hands each
// prepared command to that thread through a post function and waits for the answer.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "coe/access.hpp"
#include "mdp/device.hpp"
#include "modules/cards/card_driver.hpp"
#include "modules/cards/encoder_driver.hpp"
#include "modules/rack/channel_diagnostics.hpp"
#include "modules/rack/events.hpp"
#include "modules/rack/exception_tree.hpp"
#include "modules/signals/source_factory.hpp"

namespace rackcat::mdp {
class FileRoot;
}

namespace rackcat::modules {

class StateSpacePlant;
class UartDriver;

struct RackOptions {
  // Nominal process-data cycle: plants are discretised with it and stepped as often as it
  // fits into the elapsed time.
  double cycle_time_s = 0.001;
  // Seconds since start, monotonic. Empty: std::chrono::steady_clock, read once per firmware
  // round (base/round_time.hpp).
  std::function<double()> clock;
  double fan_nominal_rpm = 3000.0;
  double cpu_temperature_c = 42.0;
  double cpu_temperature_limit_c = 85.0;   // emergency 0x4210 at or above
  double cpu_temperature_period_s = 30.0;  // guide §4.8: 0x2000:0F updates every 30 s
  // Where replay files of the rack file are read (default: the rack file's own directory).
  std::shared_ptr<const mdp::FileRoot> files;
};

using PostFn = std::function<void(std::function<void()>)>;
// Requested ESM change (e.g. OP -> SAFEOP with AL status 0x0070 and the error flag).
using StateRequestFn = std::function<void(EsmState to, uint16_t al_status_code)>;

struct RimStatus {
  uint8_t number = 0;
  RimState state = RimState::Online;
  bool comm_error = false;
  bool power_supply_fan = false;
  bool slot_card_fan = true;
  double power_supply_rpm = 0.0;
  double slot_card_rpm = 0.0;
  uint32_t mcm_errors = 0;        // active 0x2rr1:08 bits 16..19 (SLOT machine / SOUT compare)
  bool fault_error = false;       // ERROR because of an unsafe wiring fault (ends with it)
  std::vector<uint16_t> modules;  // module numbers in this RIM
};

class Rack : public mdp::CycleListener {
 public:
  // Builds the drivers and the sources of the rack file's channel options. Throws
  // mdp::ConfigError (file:line) for a bad source description.
  explicit Rack(mdp::Device& device, RackOptions options = {});
  ~Rack() override;
  Rack(const Rack&) = delete;
  Rack& operator=(const Rack&) = delete;

  void set_state_request_handler(StateRequestFn fn) { state_request_ = std::move(fn); }
  // Veto for AL state requests the device accepted: with Detect Modules Override 0 a RIM
  // with mapped process data must be online for SAFEOP -> OP (guide §4.4). 0 = accept.
  uint16_t check_state_request(EsmState from, EsmState to) const;

  // Pseudo-terminals of the UART channels (logged: "UART module 19 channel 0: /dev/pts/4").
  void start_uart_ptys();

  // --- CycleListener (device thread).
  void on_outputs(mdp::Device&) override;
  void before_inputs(mdp::Device&) override;
  bool repeats_cycle() const override;
  // The device's own clock, independent of process data (call about once a second on the
  // device thread, in every ESM state): the 30 s CPU temperature reading (guide §4.8) and any
  // pending exception-tree update.
  void on_clock();
  void on_state_changed(mdp::Device&, EsmState from, EsmState to) override;
  void on_watchdog_expired(mdp::Device&) override;
  void on_exception_reset(mdp::Device&) override;
  void on_detect_modules(mdp::Device&) override;
  void on_parameters_loaded(mdp::Device&) override;
  void on_device_reset(mdp::Device&, bool factory) override;

  // --- State and fault injection (device thread). Every method here that can change what a
  // cycle reads (the setters, driver(), driver_at(), refresh(), sample_inputs(), enumerate(),
  // and on_clock() above) calls device().disturb() first, so a device that skips repeated
  // cycles (mdp/repeated_cycles.hpp) runs the next one in full.
  mdp::Device& device() { return device_; }
  EsmState esm_state() const { return state_; }
  bool outputs_valid() const { return outputs_valid_; }
  double now() const;
  std::span<const std::unique_ptr<CardDriver>> drivers() const { return drivers_; }
  CardDriver* driver(uint16_t module_number);
  CardDriver* driver_at(uint8_t rim, uint8_t slot);
  const std::map<uint8_t, RimStatus>& rims() const { return rims_; }
  const ExceptionTree& exceptions() const { return tree_; }

  // Replace an input channel's source; throws std::invalid_argument with the reason. A
  // `prebuilt` source (built off the device thread, e.g. a replay recording the control API
  // read) is installed instead of building one from kind/params.
  void set_source(uint16_t module, size_t channel, std::string_view kind,
                  const SourceParams& params, std::unique_ptr<Source> prebuilt = nullptr);
  void set_rim_state(uint8_t rim, RimState state, bool comm_error = false);
  // zone: "power_supply", "slot_card" for RIMs; rim 0 = the control module's CPU fan.
  void set_fan_rpm(uint8_t rim, std::string_view zone, double rpm);
  // The RIM safety controllers' errors (0x2rr1:08 bits 16..19, rim_event::kSlotMachineMcm0 ...).
  void set_rim_mcm_errors(uint8_t rim, uint32_t bits);
  double cpu_fan_rpm() const { return cpu_fan_rpm_; }
  void set_cpu_temperature(double celsius, bool publish_now);
  double cpu_temperature() const { return cpu_temp_; }
  double cpu_temperature_published() const { return cpu_temp_published_; }
  void set_wiring_fault(uint16_t module, size_t channel, WiringFault fault);
  void set_sensor_open(uint16_t module, size_t channel, bool open);
  void set_loop_ohms(uint16_t module, size_t channel, double ohms);
  // Output overload / overtemperature of an output channel (channel diagnosis, 0x10F3).
  // Throws std::invalid_argument for a module or channel without outputs.
  void set_output_fault(uint16_t module, size_t channel, bool overload, bool overtemperature);
  // Encoder faults (modules/cards/encoder_driver.hpp): hardware error, position jump by
  // `jump_steps` physical steps, frozen position. Throws std::invalid_argument when the module
  // is no encoder card.
  void set_encoder_fault(uint16_t module, EncoderFault fault, bool active, int64_t jump_steps = 0);
  bool detect_modules_override() const;
  // Module enumeration (guide Table 23): with Detect Modules Override 0 the modules of the
  // online RIMs, else all; handed to the device (mdp/module_enumeration.hpp).
  void enumerate(mdp::Device& device);
  // Modules with process data in the current 0x1C12/0x1C13 assignment.
  bool rim_has_mapped_process_data(uint8_t rim) const;
  // Publish everything derived (fans, event status, exception tree) now; the control API
  // calls it so changes show up in PREOP too, where no process data runs.
  void refresh();
  // Inputs of driver i at t: sampled with its RIM online, else the card's code for a missing
  // source; then the substitute values (mdp/substitute_values.hpp).
  void update_inputs(size_t i, double t, double dt);
  // Samples one module's inputs now (its sources at the current time), so an answer to a
  // change shows the state after it, in OP too.
  void sample_inputs(uint16_t module);

 private:
  OutputRef output_ref(uint8_t rim, uint8_t slot, uint8_t channel);
  StateSpacePlant& plant(const std::string& name, const SourceParams& params);
  SourceContext source_context();
  void apply_safe_states();
  void publish_fans();
  void publish_cpu_temperature();
  void evaluate_faults();
  // Whether module i's RIM is online (its sources present, its outputs driven).
  bool module_online(size_t i) const { return cycle_[i].rim_online; }

  // What on_outputs/before_inputs read every cycle, side by side and first (issue 16: a line
  // of racks is bound by the cache lines each slave's round touches, not by instructions).
  EsmState state_ = EsmState::Init;
  bool outputs_valid_ = false;
  bool dirty_ = true;
  bool settled_ = false;                  // the last full cycle would repeat itself (repeats_cycle)
  mutable bool cards_checked_ = false;    // cards_invariant_ holds since the last full cycle
  mutable bool cards_invariant_ = false;  // every card is time_invariant()
  bool uart_cards_ = false;        // a UART card: its queues fill from terminals, never settled
  bool fault_error_seen_ = false;  // a RIM went to ERROR for a wiring fault once
  // The cyclic walk over the modules: each one's driver and rims_[its RIM].state == Online,
  // kept by set_rim_state (one array instead of the drivers, the module -> RIM map and the
  // RIM states). Index = module number - 1.
  struct CycleCard {
    CardDriver* driver;
    bool rim_online;
  };
  std::vector<CycleCard> cycle_;
  double t0_ = 0.0;
  double last_t_ = 0.0;
  double plant_t_ = 0.0;
  double cpu_next_publish_ = 0.0;
  std::chrono::steady_clock::time_point start_;  // now() = 0 (the default clock)
  RackOptions options_;                          // now() asks its clock
  std::vector<uint16_t> fault_drivers_;          // drivers that detect wiring faults (by card kind)
  std::map<std::string, std::unique_ptr<StateSpacePlant>> plants_;
  std::optional<ChannelDiagnostics> channel_diag_;  // after drivers_ exist
  mdp::Device& device_;
  std::vector<std::unique_ptr<CardDriver>> drivers_;  // index = module number - 1
  std::vector<uint8_t> module_rim_;                   // index = module number - 1
  std::vector<uint32_t> last_safe_, last_unsafe_;

  std::vector<UartDriver*> uarts_;
  std::map<uint8_t, RimStatus> rims_;
  ExceptionTree tree_;
  StateRequestFn state_request_;
  double cpu_fan_rpm_;
  double cpu_temp_;
  double cpu_temp_published_ = 0.0;
  bool over_temperature_ = false;
};

}  // namespace rackcat::modules
