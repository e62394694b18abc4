// A slave of the line the control API serves that is not a Fusion.IO rack: a device built from
// its ESI (device/generic_device.hpp, adapted in apps/line/io_device_adapter.hpp). Its process
// data is all the API shows of it: the outputs the master wrote (read back) and the inputs the
// master reads (settable). docs/LINE.md "Control".
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace rackcat::modules {

class IoDevice {
 public:
  virtual ~IoDevice() = default;
  // "ORDER CODE 'Name'", for listings and errors.
  virtual std::string describe() const = 0;
  // The outputs the master last wrote (SM2 bytes) and the inputs it reads (SM3 bytes).
  virtual std::vector<uint8_t> outputs() const = 0;
  virtual std::vector<uint8_t> inputs() const = 0;
  // Replaces input bits [bit, bit+bits) with bits [0, bits) of `data` (LSB first, EtherCAT bit
  // order). The caller has checked the range against inputs().
  virtual void set_input_bits(size_t bit, size_t bits, std::span<const uint8_t> data) = 0;
};

}  // namespace rackcat::modules
