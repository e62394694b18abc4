// A line of emulated slaves in one process: the frame enters slave 0 at port 0, passes every
// slave's processing unit in order, and comes back out of slave 0 (ETG.1000.4 §5.1). Each
// slave is what a real one is: an ESC (ecat/esc), the firmware behind its PDI (ecat/slave)
// and the device (Application). The firmware runs between frames and at timer events, as a
// microcontroller does between the frames its ESC processes. Timers (SYNC0/1, watchdogs) are
// scheduled through one next-event bound for the whole line, not by a walk over every ESC per
// frame (next_event_bound_ns()). Logical datagrams (LRD/LWR/LRW) go only to the ESCs whose
// FMMUs meet them, found in the line's logical-address map (logical_map.hpp).
//
// Typical use by a link:
//   rackcat::ecat::Segment segment({&device_a, &device_b});
//   size_t n = segment.process(frame);            // in place; send frame[0..n) back, 0 = drop
//   segment.after_frame();                        // once it is sent: the slaves' firmware runs
//   timer at segment.next_event_bound_ns(): segment.service();
// Not thread-safe: process(), service() and every Esc/Application call belong to one thread
// (the link's event loop); other threads post work to it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "ecat/application.hpp"
#include "ecat/clock.hpp"
#include "ecat/esc/esc.hpp"
#include "ecat/esc/esc_pdi.hpp"
#include "ecat/esc/lan9252_model.hpp"
#include "ecat/frame.hpp"
#include "ecat/lan9252/lan9252_pdi.hpp"
#include "ecat/logical_map.hpp"
#include "ecat/slave/esm_event_log.hpp"
#include "ecat/slave/firmware.hpp"

namespace rackcat::ecat {

// How each slave's firmware reaches its ESC.
enum class PdiAccess : uint8_t {
  Direct,           // the chip model's PDI as such (EscPdi)
  Lan9252Emulated,  // through the LAN9252 host-bus protocol (Lan9252Pdi over Lan9252Model)
};

struct SegmentOptions {
  // Modelled propagation (ns), used for the DC receive-time latches: through a slave from
  // port 0 via the processing unit to port 1, back from port 1 to port 0, and per cable.
  uint32_t forward_delay_ns = 320;
  uint32_t return_delay_ns = 280;
  uint32_t cable_delay_ns = 10;
  // Slave k's local clock reads k x this at construction (slaves power up at different times).
  uint64_t power_on_spacing_ns = 1'234'567;
  EscOptions esc;  // identification and SII options of every slave
  PdiAccess pdi = PdiAccess::Direct;
};

class Segment {
 public:
  // One slave of the line: its ESC, the firmware behind the ESC's PDI and the device.
  class Slave {
   public:
    Slave(Application& app, const Clock& clock, const EscOptions& options, PdiAccess pdi);
    Esc& esc() { return esc_; }
    const Esc& esc() const { return esc_; }
    Firmware& firmware() { return firmware_; }
    const Firmware& firmware() const { return firmware_; }
    Application& application() const { return app_; }
    // The firmware's main loop, once: after the ESC reset (its reset output restarts the
    // microcontroller), then its events.
    void run_firmware() {
      if (esc_.take_reset()) firmware_.power_on();
      firmware_.poll();
    }
    // The same, only when the microcontroller has something to do: the ESC's reset output, or
    // Firmware::wants_service() (its IRQ line, status polling, a pending mailbox message).
    void run_firmware_if_due() {
      if (esc_.reset_pending() || firmware_.wants_service()) run_firmware();
    }
    // What the next firmware of a round reads first (its flags, the ESC's event and SM
    // registers), fetched while the one before it runs.
    void prefetch_firmware() const {
      __builtin_prefetch(&firmware_);
      esc_.prefetch();
    }

   private:
    // The EEPROM next to the ESC holds the device's SII image.
    struct Eeprom final : SiiEeprom {
      explicit Eeprom(Application& a) : app(a) {}
      std::span<const uint8_t> image() const override { return app.eeprom(); }
      void on_write(uint16_t word, std::span<const uint8_t> data) override {
        app.on_eeprom_write(word, data);
      }
      Application& app;
    };
    PdiPort& make_pdi(PdiAccess access);
    Application& app_;
    Eeprom eeprom_;
    Esc esc_;
    EscPdi pdi_;
    std::unique_ptr<Lan9252Model> lan9252_;
    std::unique_ptr<Lan9252Pdi> lan9252_pdi_;
    Firmware firmware_;
    EsmEventLog event_log_{firmware_};  // the firmware's observer unless one is set
  };

  // `applications` in line order (position 0 is next to the master); they and `clock` must
  // outlive the segment. At least one slave.
  explicit Segment(std::vector<Application*> applications,
                   const Clock& clock = SteadyClock::instance(), SegmentOptions options = {});
  // The ESCs keep pointers to the segment's next-event bound and FMMU generation: not
  // copyable, not movable.
  Segment(const Segment&) = delete;
  Segment& operator=(const Segment&) = delete;

  // Processes one Ethernet frame in place, as the line would, and returns the length of the
  // frame that comes back to the master: frame.size() for EtherCAT frames (full length, bit
  // 0x02 of the first source-MAC byte set), 0 for frames the ESCs do not answer (other
  // EtherTypes, runts). Malformed EtherCAT frames never crash: complete datagrams before the
  // defect are processed, the rest passes unchanged and every slave counts a frame error.
  // Logical datagrams are handed to the ESCs the logical-address map names (rebuilt first when
  // an FMMU changed; a frame that changes an FMMU finishes with every ESC walking its own
  // FMMUs, as the map is stale from there on). Allocates nothing. Fires due SYNC events and
  // watchdogs first when the next-event bound has come (see service()).
  size_t process(std::span<uint8_t> frame);
  // The firmware of every slave the last frame passed runs here, after its reply has left
  // (the event loop calls it once the frame is sent), for those slaves whose firmware has
  // work (Firmware::wants_service: an ESC event on its IRQ line, a mailbox message pending): a
  // microcontroller works between frames, so a slow mailbox service (a device reset, a store) never
  // delays the reply, which SOEM drops when it comes later than 2 ms. process() runs what a caller
  // left pending first, unless deferred firmware is on (set_deferred_firmware).
  void after_frame();
  // Deferred firmware (the event loop's mode, ecat/host/runner.cpp): process() no longer runs
  // the firmware work earlier frames left; the caller runs it in bounded slices between frames
  // (run_firmware_slice) and answers a frame that arrives meanwhile first. Each slave's
  // microcontroller is independent of the ESC, as on real hardware: a frame that comes before
  // a slave's firmware ran sees that slave's ESC as the firmware left it (SM3: the last input
  // buffer it completed, ETG.1000.4 §6.7.2 three-buffer mode; SM2: the newest complete output
  // buffer is read when the firmware gets to it).
  void set_deferred_firmware(bool on) { deferred_firmware_ = on; }
  // Runs the firmware of the slaves the frames since the last complete round passed, in round-
  // robin order from where the previous slice stopped: at least one slave, then more until
  // `budget_ns` of clock time has gone by. Returns true while slaves of the current round are
  // left. A frame restarts the round at the cursor (every slave it passed is run after it; no
  // slave waits more than one round). Allocates nothing.
  bool run_firmware_slice(uint64_t budget_ns);
  bool firmware_pending() const { return round_left_ != 0; }

  // Fires the SYNC events and watchdog expiries due now (clock time) and recomputes the
  // next-event bound. Call at next_event_bound_ns(); process() calls it too when the bound is
  // due.
  void service();
  // Clock time of the earliest pending SYNC event or watchdog deadline of any slave;
  // UINT64_MAX when none. Walks every ESC (tests, diagnostics).
  uint64_t next_event_ns() const;
  // A time at or before the earliest pending timer event of any slave, in O(1): exact after
  // service(), lowered by every ESC that arms a timer (Esc::set_next_event_bound), left early
  // by timers that are cancelled or retriggered later (the watchdog, every cycle) - then
  // service() at that time finds nothing due and computes the exact time. The event loop's
  // timer deadline (ecat/host/runner.cpp): no walk over the ESCs per frame.
  uint64_t next_event_bound_ns() const { return next_event_bound_; }
  // Clock time of the earliest pending SYNC0/SYNC1 event of any slave; UINT64_MAX when none.
  uint64_t next_sync_event_ns() const;

  size_t size() const { return slaves_.size(); }
  Slave& slave(size_t position) { return *slaves_.at(position); }
  const Slave& slave(size_t position) const { return *slaves_.at(position); }
  const Clock& clock() const { return clock_; }
  // The line's logical-address map as last built (tests).
  const LogicalMap& logical_map() const { return logical_map_; }

 private:
  void service_slave(Slave& s, uint64_t now);
  void service_at(uint64_t now);  // every slave, then the exact next-event bound
  void rebuild_logical_map();
  // Resolves the frame's logical datagrams through the map; false when it has none.
  bool resolve_logical(const uint8_t* base);
  // process()'s walk of the line with the frame starting at `base` (its datagrams in layout_,
  // `mapped`: resolve_logical found logical ones), arriving at slave 0 at t0: the number of
  // slaves it passed.
  size_t pass_datagrams(uint8_t* base, bool mapped, uint64_t t0);
  // The same for a frame whose only datagram is a logical one the map resolved to `targets`
  // (the master's cyclic frame), arriving at slave 0 at t0: the slaves it passed.
  size_t pass_cyclic_datagram(uint8_t* datagram, uint16_t len,
                              const std::vector<LogicalMap::Target>& targets, uint64_t t0);
  const Clock& clock_;
  SegmentOptions options_;
  std::vector<std::unique_ptr<Slave>> slaves_;
  // Firmware work the frames left (after_frame, run_firmware_slice): slaves 0..round_span_-1,
  // round_left_ of them still to run this round, the next one at cursor_.
  size_t round_span_ = 0;
  size_t round_left_ = 0;
  size_t cursor_ = 0;
  bool deferred_firmware_ = false;
  uint64_t next_event_bound_ = 0;   // <= every slave's next timer event (0: walk at once)
  std::vector<PassTimes> offsets_;  // per slave, relative to the frame's arrival at slave 0
  FrameLayout layout_;
  // Logical addressing: ESCs bump fmmu_generation_ when an FMMU may have changed; the map was
  // built for map_generation_. Per datagram of the current frame: its targets (nullptr: not a
  // logical datagram resolved through the map) and the next target not yet reached.
  LogicalMap logical_map_;
  uint32_t fmmu_generation_ = 0;
  uint32_t map_generation_ = ~0u;
  std::array<const std::vector<LogicalMap::Target>*, FrameLayout::kMaxDatagrams> targets_{};
  std::array<uint32_t, FrameLayout::kMaxDatagrams> next_target_{};
};

}  // namespace rackcat::ecat
