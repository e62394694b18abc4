#include "modules/canopen/socketcan.hpp"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rackcat::modules::canopen {

namespace {
std::runtime_error failure(const std::string& interface, const char* what) {
  return std::runtime_error("CAN interface " + interface + ": " + what + ": " +
                            std::strerror(errno));
}
}  // namespace

bool SocketCanBus::available() {
  const int fd = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd < 0) {
    return false;
  }
  ::close(fd);
  return true;
}

SocketCanBus::SocketCanBus(const std::string& interface) : interface_(interface) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    errno = EINVAL;
    throw failure(interface, "bad interface name");
  }
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd_ < 0) {
    throw failure(interface, "socket(PF_CAN, SOCK_RAW, CAN_RAW)");
  }
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, interface.c_str(), interface.size() + 1);
  if (::ioctl(fd_, SIOCGIFINDEX, &ifr) < 0) {
    ::close(fd_);
    throw failure(interface, "no such interface");
  }
  const can_err_mask_t errors = CAN_ERR_MASK;
  ::setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof errors);
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = ifr.ifr_ifindex;
  if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) < 0) {
    ::close(fd_);
    throw failure(interface, "bind");
  }
}

SocketCanBus::~SocketCanBus() {
  if (fd_ >= 0) {
    ::close(fd_);
  }
}

bool SocketCanBus::send(const CanFrame& frame) {
  can_frame f{};
  f.can_id = frame.id & CAN_SFF_MASK;
  f.can_dlc = frame.len;
  std::memcpy(f.data, frame.data.data(), frame.len);
  if (::write(fd_, &f, sizeof f) != static_cast<ssize_t>(sizeof f)) {
    ++status_.tx_dropped;  // ENOBUFS/EAGAIN: the queue is full (nobody ACKs, or bus-off)
    return false;
  }
  ++status_.tx_frames;
  return true;
}

bool SocketCanBus::receive(CanFrame& frame) {
  for (;;) {
    can_frame f{};
    const ssize_t n = ::read(fd_, &f, sizeof f);
    if (n != static_cast<ssize_t>(sizeof f)) {
      return false;  // EAGAIN (nothing pending) or a CAN FD frame we do not speak
    }
    if (f.can_id & CAN_ERR_FLAG) {
      on_error_frame(f.can_id, f.data);
      continue;
    }
    if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) {
      continue;  // CANopen uses 11-bit data frames only
    }
    frame.id = f.can_id & CAN_SFF_MASK;
    frame.len = f.can_dlc > 8 ? 8 : f.can_dlc;
    std::memcpy(frame.data.data(), f.data, frame.len);
    ++status_.rx_frames;
    return true;
  }
}

void SocketCanBus::on_error_frame(uint32_t id, const uint8_t* data) {
  ++status_.error_frames;
  if (id & CAN_ERR_BUSOFF) {
    status_.bus_off = true;
  }
  if (id & CAN_ERR_RESTARTED) {
    status_.bus_off = false;
    status_.error_passive = false;
  }
  if (id & CAN_ERR_CRTL) {
    const uint8_t ctrl = data[1];
    if (ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE)) {
      status_.error_passive = true;
    }
#ifdef CAN_ERR_CRTL_ACTIVE
    if (ctrl & CAN_ERR_CRTL_ACTIVE) {
      status_.error_passive = false;
    }
#endif
  }
}

void SocketCanBus::wait(Micros timeout_us) {
  pollfd p{fd_, POLLIN, 0};
  const int ms = static_cast<int>((timeout_us + 999) / 1000);
  ::poll(&p, 1, ms < 0 ? 0 : ms);
}

}  // namespace rackcat::modules::canopen
