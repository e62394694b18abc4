// The UART card: FIFOs through 0x5nn7..0x5nnE and the status words, control (hold, flush),
// error details, configuration applied to the channel's pseudo-terminal (guide §2.7-2.8, §4.1).
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "modules/cards/uart_driver.hpp"
#include "rack_fixture.hpp"

using namespace rackcat;
using namespace rackcat::modules;
using namespace rackcat::modules::testing;

namespace {

class UartTest : public RackTest {
 protected:
  UartDriver& uart() { return dynamic_cast<UartDriver&>(at(1, 19)); }
  coe::Object& rx(size_t ch) { return module_obj(uart(), 0x5000, static_cast<uint8_t>(0xB + ch)); }
  coe::Object& tx(size_t ch) { return module_obj(uart(), 0x5000, static_cast<uint8_t>(0x7 + ch)); }
  coe::Object& info() { return module_obj(uart(), 0x5000, 0x6); }
  uint16_t status_pdo(size_t ch) {
    return static_cast<uint16_t>(
        module_obj(uart(), 0x6000, 0xA).get_u(static_cast<uint8_t>(ch + 1)));
  }
  // An SDO upload of subindex 0 of an Rx data object: the before_read hook refills it.
  std::string read_rx(size_t ch) {
    coe::Object& o = rx(ch);
    o.hooks().before_read(o, 0);
    std::string s;
    for (uint8_t k = 1; k <= o.sub0(); ++k) s.push_back(static_cast<char>(o.get_u(k)));
    return s;
  }
  // Waits (bounded) for the line thread; no timing is asserted.
  template <class F>
  bool eventually(F&& f) {
    for (int i = 0; i < 500; ++i) {
      cycle();
      if (f()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }
};

}  // namespace

TEST_F(UartTest, InjectedBytesShowInStatusWordsAndRxData) {
  const char msg[] = "hello";
  uart().inject_rx(2, reinterpret_cast<const uint8_t*>(msg), 5);
  cycle();
  EXPECT_EQ(status_pdo(2) & 0x0FFF, 5);
  EXPECT_EQ(status_pdo(2) & 0x8000, 0x8000);  // CTS
  EXPECT_EQ(info().get_u(7), status_pdo(2));  // 0x5nn6:07 = status channel 2
  EXPECT_EQ(read_rx(2), "hello");
  cycle();
  EXPECT_EQ(status_pdo(2) & 0x0FFF, 0);
  EXPECT_EQ(read_rx(2), "");
}

TEST_F(UartTest, RxOverflowAlmostFullAndFlush) {
  std::vector<uint8_t> big(5000, 'x');
  EXPECT_EQ(uart().inject_rx(0, big.data(), big.size()), 4096u);
  cycle();
  const uint16_t s = status_pdo(0);
  EXPECT_EQ(s & 0x0FFF, 4095);          // bytes available saturates at 4095
  EXPECT_EQ(s & (1u << 14), 1u << 14);  // Rx almost full
  EXPECT_EQ(s & (1u << 12), 1u << 12);  // error occurred
  EXPECT_EQ(info().get_u(9), uart::kErrRxOverflow);
  // Flush (control bit 1) empties the FIFOs and clears the error details.
  info().set_u(1, 0x02);
  info().hooks().after_write(info(), 1);
  cycle();
  EXPECT_EQ(status_pdo(0), 0x8000);
  EXPECT_EQ(info().get_u(9), 0u);
  EXPECT_EQ(info().get_u(1), 0u);  // flush bit reads back 0
}

TEST_F(UartTest, InjectedLineErrorsAreReportedPerChannel) {
  uart().inject_error(3, uart::kErrParity | uart::kErrFraming);
  cycle();
  EXPECT_EQ(info().get_u(0x0C), 0x06u);
  EXPECT_EQ(status_pdo(3) & (1u << 12), 1u << 12);
  EXPECT_EQ(status_pdo(1) & (1u << 12), 0u);
}

TEST_F(UartTest, PseudoTerminalCarriesBytesBothWays) {
  rack.start_uart_ptys();
  const std::string path = uart().channel(1).path;
  ASSERT_EQ(path.rfind("/dev/pts/", 0), 0u) << path;
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  // Serial program -> card: arrives in the Rx FIFO, the status word and 0x5nnC.
  ASSERT_EQ(::write(fd, "ping", 4), 4);
  ASSERT_TRUE(eventually([&] { return (status_pdo(1) & 0x0FFF) == 4; }));
  EXPECT_EQ(read_rx(1), "ping");
  // Card -> serial program: a complete-access write of 0x5nn8 (subindex 0 = count).
  coe::Object& t = tx(1);
  t.image()[0] = 3;
  t.set_u(1, 'a');
  t.set_u(2, 'b');
  t.set_u(3, 'c');
  t.hooks().after_write(t, -1);
  std::string got;
  ASSERT_TRUE(eventually([&] {
    char buf[16];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) got.append(buf, static_cast<size_t>(n));
    return got.size() >= 3;
  }));
  EXPECT_EQ(got, "abc");
  ::close(fd);
}

TEST_F(UartTest, TransmitHoldKeepsBytesInTheTxFifo) {
  rack.start_uart_ptys();
  const int fd = ::open(uart().channel(0).path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  info().set_u(1, 0x01);  // transmit hold
  info().hooks().after_write(info(), 1);
  const uint8_t data[2] = {'h', 'i'};
  uart().transmit(0, data, 2);
  for (int i = 0; i < 20; ++i) {
    cycle();
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(uart().channel(0).tx.size(), 2u);
  info().set_u(1, 0x00);
  info().hooks().after_write(info(), 1);
  std::string got;
  ASSERT_TRUE(eventually([&] {
    char buf[8];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) got.append(buf, static_cast<size_t>(n));
    return got.size() >= 2;
  }));
  EXPECT_EQ(got, "hi");
  ::close(fd);
}

TEST_F(UartTest, ConfigurationIsAppliedToTheTerminal) {
  rack.start_uart_ptys();
  coe::Object& cfg = module_obj(uart(), 0x5000, 0x5);
  // Channel 2 (subindices 0x0F..0x14): 115200 Bd, even parity, 7 data bits, 2 stop bits.
  cfg.set_u(0x10, 8);
  cfg.set_u(0x11, 1);
  cfg.set_u(0x12, 2);
  cfg.set_u(0x13, 1);
  cfg.hooks().after_write(cfg, -1);
  const int fd = ::open(uart().channel(2).path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  termios tio{};
  ASSERT_EQ(tcgetattr(fd, &tio), 0);
  EXPECT_EQ(cfgetospeed(&tio), B115200);
  EXPECT_EQ(cfgetispeed(&tio), B115200);
  EXPECT_TRUE(tio.c_cflag & CSTOPB);
  EXPECT_EQ(uart().channel(2).config.baud_rate(), 115200u);
  EXPECT_EQ(uart().channel(2).config.bits_per_char(), 1u + 7u + 1u + 2u);
  // 7 data bits: bit 7 of a character does not cross the line (a pty itself is 8-bit).
  ASSERT_EQ(::write(fd, "\xC1", 1), 1);
  ASSERT_TRUE(eventually([&] { return (status_pdo(2) & 0x0FFF) == 1; }));
  EXPECT_EQ(read_rx(2), "A");
  ::close(fd);
}
