// The control API's view of a device built from its ESI (modules/control/io_device.hpp over
// device::GenericDevice): its outputs read back, its inputs set from outside.
#pragma once

#include "device/generic_device.hpp"
#include "modules/control/io_device.hpp"

namespace rackcat::apps {

class GenericIoDevice final : public modules::IoDevice {
 public:
  explicit GenericIoDevice(device::GenericDevice& device) : device_(device) {}
  std::string describe() const override {
    const auto& d = device_.esi().description;
    return d.order_code + " '" + d.device_name + "'";
  }
  std::vector<uint8_t> outputs() const override { return device_.outputs(); }
  std::vector<uint8_t> inputs() const override { return device_.inputs(); }
  void set_input_bits(size_t bit, size_t bits, std::span<const uint8_t> data) override {
    device_.set_input_bits(bit, bits, data, 0);
  }

 private:
  device::GenericDevice& device_;
};

}  // namespace rackcat::apps
