// The 4-channel UART card (guide Table 3 0xF210, §2.7-2.8, §4.1).
//
// Objects (nn = module number - 1):
//   0x5nn5  configuration per channel (interface, baud, parity, data bits, stop bits, flow
//           control), writable only in PREOP (the dictionary's access bits); applied to the
//           channel's pseudo-terminal with termios after each write.
//   0x5nn6  :01-04 control (bit 0 transmit hold, bit 1 flush: empties both FIFOs and clears
//           the error details, then reads back 0), :05-08 status words, :09-0C error details
//           (bit 0 Rx overflow, 1 framing, 2 parity, 7 Tx overflow; latched until a flush).
//   0x5nn7-A Tx data channel 0-3: a write transmits. Complete access: subindex 0 = count n,
//           bytes 1..n are sent. A single subindex k >= 1: that byte is sent. Subindex 0 alone:
//           bytes 1..value of the current image are sent.
//   0x5nnB-E Rx data channel 0-3: reading subindex 0 (or complete access) moves up to 255
//           received bytes from the Rx FIFO into subindices 1..n and sets subindex 0 = n;
//           subindices k >= 1 then read those bytes.
//   0x6nnA  status words in the process data (guide Table 21/22): bits 0-11 bytes available
//           in the Rx FIFO (0-4095), 12 error, 13 Tx almost full, 14 Rx almost full (>= 3/4 of
//           4096), 15 CTS.
//
// Line side: each channel is a Linux pseudo-terminal (posix_openpt) in raw mode whose slave
// path (/dev/pts/N) a serial program opens. Baud rate, stop bits and flow control are set on
// the terminal with termios; Linux ptys force 8-bit characters without parity, so narrower
// data bits are applied by masking each character on the line. A line thread moves bytes between
// the terminal and the card's FIFOs at the configured baud rate (10-12 bit times per character);
// bytes arriving while the Rx FIFO is full are lost and set the Rx overflow bit, as on the real
// card.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "coe/entry_slot.hpp"
#include "modules/cards/byte_ring.hpp"
#include "modules/cards/card_driver.hpp"

namespace rackcat::modules {

namespace uart {
inline constexpr size_t kFifoBytes = 4096;
inline constexpr size_t kAlmostFull = kFifoBytes * 3 / 4;
inline constexpr uint8_t kErrRxOverflow = 0x01;
inline constexpr uint8_t kErrFraming = 0x02;
inline constexpr uint8_t kErrParity = 0x04;
inline constexpr uint8_t kErrTxOverflow = 0x80;
inline constexpr uint16_t kStatusError = 1u << 12;
inline constexpr uint16_t kStatusTxAlmostFull = 1u << 13;
inline constexpr uint16_t kStatusRxAlmostFull = 1u << 14;
inline constexpr uint16_t kStatusCts = 1u << 15;
// 0x5nn5 baud enumeration (DT0800): index -> bits per second.
inline constexpr std::array<uint32_t, 9> kBaudRates{1200,  2400,  4800,  9600,  19200,
                                                    31200, 38400, 57600, 115200};
}  // namespace uart

struct UartConfig {
  uint8_t interface = 0;  // 0 RS-232, 1 RS-485, 2 RS-485 terminated
  uint8_t baud = 3;       // index into kBaudRates (9600)
  uint8_t parity = 0;     // 0 none, 1 even, 2 odd
  uint8_t data_bits = 3;  // 0..3 -> 5..8
  uint8_t stop_bits = 0;  // 0 -> 1, 1 -> 2
  uint8_t flow = 0;       // 0 none, 1 Xon/Xoff, 2 RTS/CTS (guide §2.7 order)
  uint32_t baud_rate() const;
  unsigned bits_per_char() const;  // start + data + parity + stop
};

class UartDriver final : public CardDriver {
 public:
  struct Channel {
    Channel() : rx(uart::kFifoBytes), tx(uart::kFifoBytes) {}
    ByteRing rx;              // line -> card (consumer: device thread)
    ByteRing tx;              // card -> line (consumer: line thread)
    std::mutex rx_producers;  // the line thread and fault injection both push into rx
    std::atomic<uint8_t> errors{0};
    std::atomic<bool> hold{false};
    std::atomic<bool> cts{true};
    std::atomic<bool> flush_tx{false};
    std::atomic<uint32_t> baud_rate{9600};
    std::atomic<unsigned> bits_per_char{10};
    std::atomic<bool> rts_cts{false};
    std::atomic<uint8_t> data_mask{0xFF};  // 5..8 data bits
    UartConfig config;
    int master_fd = -1;
    int slave_fd = -1;  // kept open so the terminal exists while no program has it open
    std::string path;
    uint64_t rx_total = 0, tx_total = 0;  // statistics (device thread)
  };

  UartDriver(const mdp::Module& m, coe::ObjectDictionary& od);
  ~UartDriver() override;

  // Open the four pseudo-terminals and start the line thread. Throws std::runtime_error.
  void start_ptys();
  void stop_ptys();

  // Re-read 0x5nn5 (after a parameter load) and apply it to the terminals.
  void reload_config() { read_config(); }

  void write_inputs(double t, double dt) override;
  void clear_inputs() override;

  Channel& channel(size_t i) { return *channels_[i]; }
  const Channel& channel(size_t i) const { return *channels_[i]; }
  uint16_t status_word(size_t i) const;

  // Fault injection (device thread): bytes as if received on the line; error bits as if the
  // line had a framing/parity error or overflow.
  size_t inject_rx(size_t ch, const uint8_t* data, size_t n);
  void inject_error(size_t ch, uint8_t error_bits);
  // Transmit (what a 0x5nn7 write does), for tests and the control API.
  size_t transmit(size_t ch, const uint8_t* data, size_t n);

 private:
  void install_hooks();
  void read_config();
  void apply_termios(size_t ch);
  void on_control_written(int subindex);
  void refresh_status_objects();
  void line_thread();

  std::array<std::unique_ptr<Channel>, 4> channels_;
  coe::Object& status_pdo_;  // 0x6nnA
  coe::Object* config_;      // 0x5nn5
  coe::Object* info_;        // 0x5nn6
  std::array<coe::Object*, 4> tx_obj_{};
  std::array<coe::Object*, 4> rx_obj_{};
  std::array<coe::EntrySlot, 4> status_slots_, info_status_, info_errors_;
  std::vector<std::pair<coe::Object*, coe::ObjectHooks>> saved_hooks_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  int wake_fd_ = -1;
};

}  // namespace rackcat::modules
