// Puts CAN RIMs into the emulated rack: the input channels of the RIMs a RimMaster watches
// read the values of the RIMs' TPDOs (RemoteInputSource), their output channels' driven
// values go out in the RPDOs, the master's RIM states go to Rack::set_rim_state (latched
// bits, exception tree, Detect Modules Override, emergencies all follow from there), and fan
// EMCYs from a RIM set its fan speed.
//
// Fan EMCY of a RIM (docs/CAN.md): error code 0x5000 (device hardware), data byte 0 = zone
// (0 power supply, 1 slot card), bytes 1-2 = RPM (UNSIGNED16).
//
// Everything runs on the rack's device thread: call RimMaster::step there too.
#pragma once

#include "modules/rack/rack.hpp"
#include "modules/rim/master.hpp"

namespace rackcat::modules::canopen {

// A rack input channel fed from the CAN link; sample() reads the last received value.
class RemoteInputSource final : public Source {
 public:
  RemoteInputSource(const double* value, std::string name)
      : value_(value), name_(std::move(name)) {}
  double sample(double) override { return *value_; }
  std::string describe() const override { return "can " + name_; }
  bool varies_within_cycle() const override { return false; }

 private:
  const double* value_;
  std::string name_;
};

// Wires every RIM of `master` into `rack`: both must outlive the link. Throws
// std::invalid_argument when the rack lacks a card of the master's profile.
void attach_rim_master(RimMaster& master, Rack& rack);

}  // namespace rackcat::modules::canopen
