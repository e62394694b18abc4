// CAN RIMs for `rackcat run --rim-bus can:IFACE`: the RimMaster runs on its own thread (the
// ESC's event loop has no file-descriptor watches), and everything that crosses into the
// rack goes through lock-free mirrors or the rack's post function:
//   - input values: the CAN thread stores each RIM input channel into an atomic mirror after
//     every step; the rack's input channels read it (AtomicInputSource, no allocation);
//   - output values: this object is a CycleListener of the device, after the rack: at every
//     cycle it stores the driven value of each CAN output channel into an atomic mirror, which
//     the CAN thread reads before each step into the values its RPDOs carry;
//   - RIM state changes and fan EMCYs: posted to the device thread, which calls
//     Rack::set_rim_state / set_fan_rpm (latched bits, exception tree, emergencies, Detect
//     Modules Override follow).
// Tests drive it without a thread: construct with start_thread = false and call poll(now).
#pragma once

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "modules/rack/rack.hpp"
#include "modules/rim/master.hpp"

namespace rackcat::modules::canopen {

class ThreadedRimLink final : public mdp::CycleListener {
 public:
  // Installs the rack's sources and output bindings for `rims` (empty: every RIM of the rack
  // file), marks those RIMs OFFLINE until their heartbeat comes, and adds itself as a device
  // listener. Throws std::invalid_argument when the rack lacks a channel of a RIM's profile.
  ThreadedRimLink(Rack& rack, std::unique_ptr<CanBus> bus, RimMasterOptions options,
                  std::vector<uint8_t> rims, PostFn post, bool start_thread = true);
  ~ThreadedRimLink() override;
  ThreadedRimLink(const ThreadedRimLink&) = delete;
  ThreadedRimLink& operator=(const ThreadedRimLink&) = delete;

  // One step of the CAN side at `now` (the thread calls it every 200 us at most).
  void poll(Micros now);
  void stop();

  // CycleListener (device thread): publish the driven output values.
  void on_outputs(mdp::Device&) override { publish_outputs(); }
  void before_inputs(mdp::Device&) override { publish_outputs(); }

  const RimMaster& master() const { return *master_; }

 private:
  struct Channel {
    uint8_t rim, slot, channel;
  };
  class AtomicInputSource;
  void publish_outputs();
  void run();

  Rack& rack_;
  std::unique_ptr<CanBus> bus_;
  std::unique_ptr<RimMaster> master_;
  PostFn post_;
  std::vector<Channel> in_channels_, out_channels_;
  std::vector<const double*> master_inputs_;        // CAN thread
  std::unique_ptr<std::atomic<double>[]> inputs_;   // CAN thread -> device thread
  std::vector<const double*> driven_;               // device thread: the drivers' outputs
  std::unique_ptr<std::atomic<double>[]> outputs_;  // device thread -> CAN thread
  std::vector<double> rpdo_values_;                 // CAN thread: what the master sends
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace rackcat::modules::canopen
