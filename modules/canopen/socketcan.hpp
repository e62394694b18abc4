// SocketCAN transport (Linux Documentation/networking/can.rst): one PF_CAN/SOCK_RAW/CAN_RAW
// socket bound to an interface (vcan0, can0 ...), classic CAN frames only, non-blocking.
// All error classes are subscribed (CAN_RAW_ERR_FILTER = CAN_ERR_MASK): error frames are
// counted, and bus-off / error-passive (linux/can/error.h) are tracked in status().
#pragma once

#include <string>

#include "modules/canopen/bus.hpp"

namespace rackcat::modules::canopen {

class SocketCanBus final : public CanBus {
 public:
  // Throws std::runtime_error naming the interface and the errno text (no AF_CAN in the
  // kernel, no such interface, interface down).
  explicit SocketCanBus(const std::string& interface);
  ~SocketCanBus() override;
  SocketCanBus(const SocketCanBus&) = delete;
  SocketCanBus& operator=(const SocketCanBus&) = delete;

  bool send(const CanFrame& frame) override;
  bool receive(CanFrame& frame) override;
  void wait(Micros timeout_us) override;
  const BusStatus& status() const override { return status_; }

  // True when this kernel can open a CAN_RAW socket at all.
  static bool available();

 private:
  void on_error_frame(uint32_t id, const uint8_t* data);

  int fd_ = -1;
  std::string interface_;
  BusStatus status_;
};

}  // namespace rackcat::modules::canopen
