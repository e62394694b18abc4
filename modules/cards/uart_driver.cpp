#include "modules/cards/uart_driver.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>

#include "base/real_time.hpp"
#include "modules/cards/drivers.hpp"

namespace rackcat::modules {

uint32_t UartConfig::baud_rate() const {
  return baud < uart::kBaudRates.size() ? uart::kBaudRates[baud] : 9600;
}

unsigned UartConfig::bits_per_char() const {
  return 1u + (5u + std::min<unsigned>(data_bits, 3)) + (parity != 0 ? 1u : 0u) +
         (stop_bits != 0 ? 2u : 1u);
}

namespace {

// 0x5nn5: channel c occupies subindices 1 + 7c .. 6 + 7c (the seventh is padding).
uint8_t config_sub(size_t channel, unsigned field) {
  return static_cast<uint8_t>(1 + 7 * channel + field);
}

speed_t termios_speed(uint32_t baud) {
  switch (baud) {
    case 1200:
      return B1200;
    case 2400:
      return B2400;
    case 4800:
      return B4800;
    case 9600:
      return B9600;
    case 19200:
      return B19200;
    // 31200 Bd has no termios constant; the terminal reports the next standard rate while the
    // line thread paces at the exact 31200 Bd.
    case 31200:
    case 38400:
      return B38400;
    case 57600:
      return B57600;
    default:
      return B115200;
  }
}

}  // namespace

UartDriver::UartDriver(const mdp::Module& m, coe::ObjectDictionary& od)
    : CardDriver(m, od, 0, 0),
      status_pdo_(require_object(od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)),
      config_(od.find(m.index(0x5000, 5))),
      info_(od.find(m.index(0x5000, 6))) {
  for (auto& c : channels_) c = std::make_unique<Channel>();
  for (size_t c = 0; c < 4; ++c) {
    tx_obj_[c] = od.find(m.index(0x5000, static_cast<uint8_t>(0x7 + c)));
    rx_obj_[c] = od.find(m.index(0x5000, static_cast<uint8_t>(0xB + c)));
  }
  for (size_t c = 0; c < 4; ++c) {
    status_slots_[c] = coe::EntrySlot(status_pdo_, static_cast<uint8_t>(1 + c));
    if (info_ != nullptr) {
      info_status_[c] = coe::EntrySlot(*info_, static_cast<uint8_t>(5 + c));
      info_errors_[c] = coe::EntrySlot(*info_, static_cast<uint8_t>(9 + c));
    }
  }
  read_config();
  install_hooks();
}

UartDriver::~UartDriver() {
  stop_ptys();
  for (auto& [object, hooks] : saved_hooks_) object->edit_hooks() = std::move(hooks);
}

void UartDriver::read_config() {
  for (size_t c = 0; c < 4; ++c) {
    Channel& ch = *channels_[c];
    if (config_ != nullptr) {
      ch.config.interface = static_cast<uint8_t>(config_->get_u(config_sub(c, 0)));
      ch.config.baud = static_cast<uint8_t>(config_->get_u(config_sub(c, 1)));
      ch.config.parity = static_cast<uint8_t>(config_->get_u(config_sub(c, 2)));
      ch.config.data_bits = static_cast<uint8_t>(config_->get_u(config_sub(c, 3)));
      ch.config.stop_bits = static_cast<uint8_t>(config_->get_u(config_sub(c, 4)));
      ch.config.flow = static_cast<uint8_t>(config_->get_u(config_sub(c, 5)));
    }
    ch.baud_rate = ch.config.baud_rate();
    ch.bits_per_char = ch.config.bits_per_char();
    ch.rts_cts = ch.config.flow == 2;
    ch.data_mask = static_cast<uint8_t>(0xFFu >> (3 - std::min<unsigned>(ch.config.data_bits, 3)));
    apply_termios(c);
  }
}

void UartDriver::apply_termios(size_t c) {
  Channel& ch = *channels_[c];
  if (ch.slave_fd < 0) return;
  termios tio{};
  if (tcgetattr(ch.slave_fd, &tio) != 0) return;
  cfmakeraw(&tio);
  const speed_t speed = termios_speed(ch.config.baud_rate());
  cfsetispeed(&tio, speed);
  cfsetospeed(&tio, speed);
  tio.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
  static constexpr tcflag_t kSizes[4] = {CS5, CS6, CS7, CS8};
  tio.c_cflag |= kSizes[std::min<unsigned>(ch.config.data_bits, 3)] | CLOCAL | CREAD;
  if (ch.config.parity == 1) tio.c_cflag |= PARENB;
  if (ch.config.parity == 2) tio.c_cflag |= PARENB | PARODD;
  if (ch.config.stop_bits != 0) tio.c_cflag |= CSTOPB;
  if (ch.config.flow == 2) tio.c_cflag |= CRTSCTS;
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF);
  if (ch.config.flow == 1) tio.c_iflag |= IXON | IXOFF;
  tcsetattr(ch.slave_fd, TCSANOW, &tio);
}

void UartDriver::install_hooks() {
  // The dictionary outlives this driver: keep the hooks found there and put them back in the
  // destructor, so no hook calls into a destroyed driver.
  for (coe::Object* o : {config_, info_, tx_obj_[0], tx_obj_[1], tx_obj_[2], tx_obj_[3], rx_obj_[0],
                         rx_obj_[1], rx_obj_[2], rx_obj_[3]}) {
    if (o != nullptr) saved_hooks_.emplace_back(o, o->hooks());
  }
  if (config_ != nullptr) {
    auto previous = config_->hooks().after_write;
    config_->edit_hooks().after_write = [this, previous](coe::Object& o, int sub) {
      if (previous) previous(o, sub);
      read_config();
    };
  }
  if (info_ != nullptr) {
    auto prev_write = info_->hooks().after_write;
    info_->edit_hooks().after_write = [this, prev_write](coe::Object& o, int sub) {
      if (prev_write) prev_write(o, sub);
      on_control_written(sub);
    };
    auto prev_read = info_->hooks().before_read;
    info_->edit_hooks().before_read = [this, prev_read](coe::Object& o, int sub) {
      if (prev_read) prev_read(o, sub);
      refresh_status_objects();
    };
  }
  for (size_t c = 0; c < 4; ++c) {
    if (coe::Object* tx = tx_obj_[c]) {
      auto previous = tx->hooks().after_write;
      tx->edit_hooks().after_write = [this, previous, c](coe::Object& o, int sub) {
        if (previous) previous(o, sub);
        uint8_t bytes[255];
        size_t n = 0;
        if (sub >= 1) {
          bytes[n++] = static_cast<uint8_t>(o.get_u(static_cast<uint8_t>(sub)));
        } else {
          const size_t count = std::min<size_t>(o.sub0(), o.max_subindex());
          for (size_t k = 1; k <= count; ++k)
            bytes[n++] = static_cast<uint8_t>(o.get_u(static_cast<uint8_t>(k)));
        }
        transmit(c, bytes, n);
      };
    }
    if (coe::Object* rx = rx_obj_[c]) {
      auto previous = rx->hooks().before_read;
      rx->edit_hooks().before_read = [this, previous, c](coe::Object& o, int sub) {
        if (previous) previous(o, sub);
        if (sub > 0) return;  // entries read what the last subindex-0 read delivered
        uint8_t bytes[255];
        const size_t room = std::min<size_t>(255, o.max_subindex());
        Channel& ch = *channels_[c];
        const size_t n = ch.rx.pop(bytes, room);
        ch.rx_total += n;
        for (size_t k = 0; k < room; ++k)
          o.set_u(static_cast<uint8_t>(k + 1), k < n ? bytes[k] : 0);
        o.image()[0] = static_cast<uint8_t>(n);
      };
    }
  }
}

void UartDriver::on_control_written(int sub) {
  if (info_ == nullptr) return;
  for (size_t c = 0; c < 4; ++c) {
    const auto s = static_cast<uint8_t>(1 + c);
    if (sub > 0 && sub != s) continue;
    const auto control = static_cast<uint8_t>(info_->get_u(s));
    Channel& ch = *channels_[c];
    ch.hold = (control & 0x01) != 0;
    if (control & 0x02) {
      // Flush: both FIFOs emptied, error details cleared; the bit reads back 0.
      ch.rx.clear();
      ch.flush_tx = true;
      ch.errors = 0;
      info_->set_u(s, control & ~0x02u);
      if (wake_fd_ >= 0) {
        const uint64_t one = 1;
        (void)!::write(wake_fd_, &one, sizeof one);
      }
    }
  }
  refresh_status_objects();
}

uint16_t UartDriver::status_word(size_t c) const {
  const Channel& ch = *channels_[c];
  const size_t rx = ch.rx.size();
  uint16_t w = static_cast<uint16_t>(std::min<size_t>(rx, 4095));
  if (ch.errors.load(std::memory_order_relaxed) != 0) w |= uart::kStatusError;
  if (ch.tx.size() >= uart::kAlmostFull) w |= uart::kStatusTxAlmostFull;
  if (rx >= uart::kAlmostFull) w |= uart::kStatusRxAlmostFull;
  if (ch.cts.load(std::memory_order_relaxed)) w |= uart::kStatusCts;
  return w;
}

void UartDriver::refresh_status_objects() {
  for (size_t c = 0; c < 4; ++c) {
    const uint16_t w = status_word(c);
    status_slots_[c].set(w);
    info_status_[c].set(w);
    info_errors_[c].set(channels_[c]->errors.load(std::memory_order_relaxed));
  }
}

void UartDriver::write_inputs(double, double) {
  refresh_status_objects();
}

void UartDriver::clear_inputs() {
  for (size_t c = 0; c < 4; ++c) status_pdo_.set_u(static_cast<uint8_t>(1 + c), 0);
}

size_t UartDriver::inject_rx(size_t c, const uint8_t* data, size_t n) {
  Channel& ch = *channels_[c];
  std::lock_guard lock(ch.rx_producers);
  const size_t pushed = ch.rx.push(data, n);
  if (pushed < n) ch.errors |= uart::kErrRxOverflow;
  return pushed;
}

void UartDriver::inject_error(size_t c, uint8_t bits) {
  channels_[c]->errors |= bits;
}

size_t UartDriver::transmit(size_t c, const uint8_t* data, size_t n) {
  Channel& ch = *channels_[c];
  const size_t pushed = ch.tx.push(data, n);
  ch.tx_total += pushed;
  if (pushed < n) ch.errors |= uart::kErrTxOverflow;
  if (wake_fd_ >= 0 && pushed > 0) {
    const uint64_t one = 1;
    (void)!::write(wake_fd_, &one, sizeof one);
  }
  return pushed;
}

void UartDriver::start_ptys() {
  if (running_) return;
  for (size_t c = 0; c < 4; ++c) {
    Channel& ch = *channels_[c];
    ch.master_fd = posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    if (ch.master_fd < 0 || grantpt(ch.master_fd) != 0 || unlockpt(ch.master_fd) != 0) {
      const int err = errno;
      stop_ptys();
      throw std::runtime_error(fmt::format("module {}: cannot open a pseudo-terminal: {}",
                                           module_.number, std::strerror(err)));
    }
    char name[128];
    if (ptsname_r(ch.master_fd, name, sizeof name) != 0) {
      stop_ptys();
      throw std::runtime_error(fmt::format("module {}: ptsname failed", module_.number));
    }
    ch.path = name;
    ch.slave_fd = ::open(name, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
    apply_termios(c);
  }
  wake_fd_ = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  running_ = true;
  thread_ = std::thread([this] { line_thread(); });
}

void UartDriver::stop_ptys() {
  if (running_.exchange(false)) {
    const uint64_t one = 1;
    (void)!::write(wake_fd_, &one, sizeof one);
    thread_.join();
  }
  for (auto& c : channels_) {
    if (c->slave_fd >= 0) ::close(c->slave_fd);
    if (c->master_fd >= 0) ::close(c->master_fd);
    c->slave_fd = c->master_fd = -1;
  }
  if (wake_fd_ >= 0) ::close(wake_fd_);
  wake_fd_ = -1;
}

// Moves bytes between the terminals and the FIFOs at the configured character rate: a token
// bucket per direction and channel, refilled with baud / bits-per-character per second.
void UartDriver::line_thread() {
  (void)base::leave_real_time();  // a helper thread, not the device thread
  using clock = std::chrono::steady_clock;
  struct Bucket {
    double rx = 0, tx = 0;
  };
  std::array<Bucket, 4> buckets{};
  auto last = clock::now();
  while (running_) {
    pollfd fds[5];
    nfds_t n = 0;
    fds[n++] = {wake_fd_, POLLIN, 0};
    for (auto& c : channels_) fds[n++] = {c->master_fd, POLLIN, 0};
    // Wake at least every 2 ms while there is data to pace out.
    bool pending = false;
    for (auto& c : channels_) pending |= c->tx.size() > 0;
    ::poll(fds, n, pending ? 2 : 50);
    if (fds[0].revents & POLLIN) {
      uint64_t v;
      (void)!::read(wake_fd_, &v, sizeof v);
    }
    const auto now = clock::now();
    const double elapsed = std::chrono::duration<double>(now - last).count();
    last = now;
    for (size_t c = 0; c < 4; ++c) {
      Channel& ch = *channels_[c];
      const double rate = static_cast<double>(ch.baud_rate.load()) / ch.bits_per_char.load();
      // A burst of at most 64 characters after idle time, like a small line buffer.
      buckets[c].rx = std::min(buckets[c].rx + elapsed * rate, 64.0);
      buckets[c].tx = std::min(buckets[c].tx + elapsed * rate, 64.0);
      if (ch.flush_tx.exchange(false)) {
        uint8_t sink[256];
        while (ch.tx.pop(sink, sizeof sink) > 0) {
        }
      }
      // Line -> Rx FIFO.
      if (fds[1 + c].revents & POLLIN) {
        const auto budget = static_cast<size_t>(buckets[c].rx);
        if (budget > 0) {
          uint8_t buf[64];
          const ssize_t got = ::read(ch.master_fd, buf, std::min(budget, sizeof buf));
          if (got > 0) {
            // Linux ptys are always 8-bit clean (pty_set_termios forces CS8, no parity), so
            // narrower character sizes are applied here: the upper bits never cross the line.
            const uint8_t mask = ch.data_mask.load();
            for (ssize_t i = 0; i < got; ++i) buf[i] &= mask;
            buckets[c].rx -= static_cast<double>(got);
            std::lock_guard lock(ch.rx_producers);
            if (ch.rx.push(buf, static_cast<size_t>(got)) < static_cast<size_t>(got))
              ch.errors |= uart::kErrRxOverflow;  // the FIFO was full: characters lost
          }
        }
      }
      // Tx FIFO -> line, unless held (control bit 0) or CTS deasserted with RTS/CTS.
      const bool blocked = ch.hold.load() || (ch.rts_cts.load() && !ch.cts.load());
      const auto budget = static_cast<size_t>(buckets[c].tx);
      if (!blocked && budget > 0 && ch.tx.size() > 0) {
        uint8_t buf[64];
        const size_t k = ch.tx.peek(buf, std::min(budget, sizeof buf));
        const uint8_t mask = ch.data_mask.load();
        for (size_t i = 0; i < k; ++i) buf[i] &= mask;
        const ssize_t put = ::write(ch.master_fd, buf, k);
        if (put > 0) {
          ch.tx.pop(buf, static_cast<size_t>(put));
          buckets[c].tx -= static_cast<double>(put);
        }
      }
    }
  }
}

std::unique_ptr<CardDriver> make_uart_driver(const mdp::Module& m, coe::ObjectDictionary& od) {
  return std::make_unique<UartDriver>(m, od);
}

}  // namespace rackcat::modules
