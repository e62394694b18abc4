#include "modules/rim/threaded_link.hpp"

#include <fmt/format.h>

#include <chrono>
#include <stdexcept>

#include "coe/bits.hpp"

namespace rackcat::modules::canopen {

class ThreadedRimLink::AtomicInputSource final : public Source {
 public:
  AtomicInputSource(const std::atomic<double>* value, std::string name)
      : value_(value), name_(std::move(name)) {}
  double sample(double) override { return value_->load(std::memory_order_relaxed); }
  std::string describe() const override { return "can " + name_; }
  bool varies_within_cycle() const override { return false; }

 private:
  const std::atomic<double>* value_;
  std::string name_;
};

ThreadedRimLink::ThreadedRimLink(Rack& rack, std::unique_ptr<CanBus> bus, RimMasterOptions options,
                                 std::vector<uint8_t> rims, PostFn post, bool start_thread)
    : rack_(rack),
      bus_(std::move(bus)),
      master_(std::make_unique<RimMaster>(rack.device().config(), *bus_, options, std::move(rims))),
      post_(std::move(post)) {
  for (uint8_t r : master_->rims()) {
    const RimProfile& p = *master_->profile(r);
    for (const RimChannel& c : p.inputs) in_channels_.push_back({r, c.slot, c.channel});
    for (const RimChannel& c : p.outputs) out_channels_.push_back({r, c.slot, c.channel});
  }
  inputs_ = std::make_unique<std::atomic<double>[]>(in_channels_.size());
  outputs_ = std::make_unique<std::atomic<double>[]>(out_channels_.size());
  rpdo_values_.assign(out_channels_.size(), 0.0);
  for (size_t i = 0; i < in_channels_.size(); ++i) {
    const Channel& c = in_channels_[i];
    CardDriver* d = rack.driver_at(c.rim, c.slot);
    if (!d || c.channel >= d->inputs().size()) {
      throw std::invalid_argument(
          fmt::format("rack has no input channel {} in RIM {} slot {}", c.channel, c.rim, c.slot));
    }
    inputs_[i].store(0.0);
    master_inputs_.push_back(master_->input_ptr(c.rim, c.slot, c.channel));
    d->set_source(c.channel,
                  std::make_unique<AtomicInputSource>(
                      &inputs_[i], fmt::format("rim{}.slot{}.in{}", c.rim, c.slot, c.channel)));
  }
  for (size_t i = 0; i < out_channels_.size(); ++i) {
    const Channel& c = out_channels_[i];
    CardDriver* d = rack.driver_at(c.rim, c.slot);
    if (!d || c.channel >= d->outputs().size()) {
      throw std::invalid_argument(
          fmt::format("rack has no output channel {} in RIM {} slot {}", c.channel, c.rim, c.slot));
    }
    outputs_[i].store(0.0);
    driven_.push_back(&d->outputs()[c.channel].driven);
    master_->bind_output(c.rim, c.slot, c.channel, &rpdo_values_[i]);
  }
  for (uint8_t r : master_->rims()) rack.set_rim_state(r, RimState::Offline, false);
  // Callbacks run on the CAN thread: the rack is touched only on the device thread.
  master_->on_state([this](uint8_t rim, RimState s, bool comm_error) {
    post_([this, rim, s, comm_error] { rack_.set_rim_state(rim, s, comm_error); });
  });
  master_->on_emergency([this](uint8_t rim, const coe::Emergency& e) {
    if (e.error_code != emcy::kFan) return;
    const char* zone = e.data[0] == 0 ? "power_supply" : "slot_card";
    const double rpm = le::get16(&e.data[1]);
    post_([this, rim, zone, rpm] {
      try {
        rack_.set_fan_rpm(rim, zone, rpm);
      } catch (const std::invalid_argument&) {
        // The rack file gives this RIM no such fan.
      }
    });
  });
  rack.device().add_listener(this);
  if (start_thread) thread_ = std::thread([this] { run(); });
}

ThreadedRimLink::~ThreadedRimLink() {
  stop();
  rack_.device().remove_listener(this);
}

void ThreadedRimLink::stop() {
  stop_.store(true);
  if (thread_.joinable()) thread_.join();
}

void ThreadedRimLink::publish_outputs() {
  for (size_t i = 0; i < driven_.size(); ++i) {
    outputs_[i].store(*driven_[i], std::memory_order_relaxed);
  }
}

void ThreadedRimLink::poll(Micros now) {
  for (size_t i = 0; i < rpdo_values_.size(); ++i) {
    rpdo_values_[i] = outputs_[i].load(std::memory_order_relaxed);
  }
  master_->step(now);
  for (size_t i = 0; i < master_inputs_.size(); ++i) {
    inputs_[i].store(*master_inputs_[i], std::memory_order_relaxed);
  }
}

void ThreadedRimLink::run() {
  const auto t0 = std::chrono::steady_clock::now();
  while (!stop_.load()) {
    bus_->wait(200);
    poll(
        std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - t0)
            .count());
  }
}

}  // namespace rackcat::modules::canopen
