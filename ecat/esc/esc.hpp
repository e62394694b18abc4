// One emulated EtherCAT slave controller (ESC), ET1100-class: the chip only. A 64 KiB address
// space (EscMemory: backed only where written) with the registers 0x0000-0x0FFF behaving as
// ETG.1000.4 §6 and the Beckhoff ESC datasheet (section II) describe them, process RAM
// 0x1000-0xFFFF, 16 FMMUs, 16 SyncManagers, the SII EEPROM interface, distributed clocks with
// SYNC0/SYNC1, the process-data watchdog, the datagram engine on the EtherCAT side and the PDI on
// the other (pdi_read/pdi_write, the IRQ line). docs/ESC.md is the one-page register model.
//
// The chip knows no AL state: AL control 0x0120 is a register the master writes (raising AL
// event request 0x0220 bit 0), AL status 0x0130/0x0134 are registers the firmware writes
// through the PDI. The firmware (ecat/slave) runs the ESM, the mailbox and the process data
// behind an EscPdi (esc_pdi.hpp), as a microcontroller behind a real ESC would.
//
// The ESC never allocates on the datagram path. It is driven by a Segment (segment.hpp), which
// hands it each datagram of each frame in line order; tests may drive it the same way.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "base/cache_line.hpp"
#include "base/little_endian.hpp"
#include "base/short_copy.hpp"
#include "ecat/clock.hpp"
#include "ecat/esc/esc_memory.hpp"
#include "ecat/frame.hpp"
#include "ecat/registers.hpp"

namespace rackcat::ecat {

// Identification values the ESC reports (0x0000-0x0009) and SII interface options.
struct EscOptions {
  uint8_t type = 0x11;             // 0x0000: ET1100
  uint8_t revision = 0x00;         // 0x0001
  uint16_t build = 0x0002;         // 0x0002
  uint8_t port_descriptor = 0x0F;  // 0x0007: ports 0 and 1 MII, ports 2 and 3 not implemented
  // 0x0008: bit 2 DC, bit 3 64-bit DC, bit 8 enhanced DC SYNC activation; LRW and the
  // read-write commands supported (bits 9, 10 clear); bit-granular FMMUs (bit 0 clear).
  uint16_t features = 0x010C;
  uint8_t sii_read_bytes = 8;  // 4 or 8: size of one SII read (0x0502 bit 6)
  // Local time at power-up, so the slaves of a segment do not share a time origin (ETG.1000.4
  // §9.1: each local clock starts at 0 when the ESC powers up).
  uint64_t power_on_local_time_ns = 0;
};

// When the frame passed this ESC, in the clock's time base: used for the DC receive-time
// latches (0x0900-0x091F) and for the system time a datagram reads.
struct PassTimes {
  uint64_t port0_ns = 0;  // first bit at port 0 (also the processing unit, 0x0918)
  uint64_t port1_ns = 0;  // the same frame coming back at port 1
};

// The SII EEPROM chip next to the ESC (ETG.2010): its content at power-on and where master
// writes through the SII interface (0x0502-0x050F) are stored.
class SiiEeprom {
 public:
  virtual ~SiiEeprom() = default;
  // Byte-addressed little-endian words; must stay valid while the ESC is constructed.
  virtual std::span<const uint8_t> image() const = 0;
  virtual void on_write(uint16_t /*word_address*/, std::span<const uint8_t> /*data*/) {}
};

class Esc {
 public:
  static constexpr size_t kMemorySize = EscMemory::kSize;
  static constexpr int kFmmus = 16;
  static constexpr int kSyncManagers = 16;

  // The EEPROM and the clock must outlive the ESC. The SII image is copied (the master may
  // write it); the power-on EEPROM load (words 0-7, ETG.1000.4 §6.4.5) runs here.
  Esc(SiiEeprom& eeprom, const Clock& clock, EscOptions options = {});
  Esc(const Esc&) = delete;
  Esc& operator=(const Esc&) = delete;

  // ---- datagram path (called by Segment for every frame passing this ESC) -----------------
  void begin_frame(const PassTimes& times) {
    pass_ = times;
    register_write_enabled_ = esc_write_enabled_ = false;  // enables last one frame
  }
  // A hint, no effect on behaviour: starts loading the state a cyclic datagram touches (the hot
  // block: flags, whole-buffer plan, SyncManagers; the event and SM registers) while the segment is
  // still busy with the slave before this one, so a long line does not wait for each ESC's memory
  // in turn.
  void prefetch() const {
    __builtin_prefetch(&pass_);
    __builtin_prefetch(&whole_plans_[last_plan_]);
    __builtin_prefetch(&sm_[0]);
    __builtin_prefetch(&mem_[reg::kEcatEventRequest]);
    __builtin_prefetch(&mem_[reg::kSm]);
  }
  // One datagram passing this ESC: `datagram` points at its 10-byte header, followed by
  // `data_len` data bytes and the 2-byte working counter. Addressing (ADP auto-increment),
  // data and working counter are updated in place per ETG.1000.4 §5.4. The IRQ field is ORed
  // with this ESC's masked ECAT event request (0x0210 & 0x0200).
  void process_datagram(uint8_t* datagram, uint16_t data_len);
  // A logical datagram (LRD, LWR, LRW) handled through the FMMUs in `fmmus` only (bit n =
  // FMMU n): those the segment's logical-address map found inside the datagram's range
  // (ecat/logical_map.hpp). Working counter and IRQ field as process_datagram; FMMUs that are
  // no longer activated are skipped. The master's cyclic LRW - the datagram the kept plan was
  // made for, when that plan is an exchange - goes straight to it.
  void process_logical_datagram(uint8_t* datagram, uint16_t data_len, uint16_t fmmus) {
    const WholePlan& p = whole_plans_[last_plan_];
    if (p.exchange && p.valid && p.len == data_len &&
        p.fmmus == static_cast<uint16_t>(fmmus & fmmu_active_mask_) &&
        datagram[0] == static_cast<uint8_t>(Command::Lrw) && p.address == le::get32(datagram + 2)) {
      exchange_datagram(datagram, data_len);
    } else {
      logical_datagram(datagram, data_len, fmmus);
    }
  }
  // A datagram that does not address this ESC (a logical one none of its FMMUs meets) passing
  // through: only the IRQ field is ORed with this ESC's masked ECAT events, as process_datagram
  // does for every datagram.
  void pass_datagram(uint8_t* datagram) const;
  // A frame this ESC could not parse (chain past the end, bad length): counts it in the
  // processing-unit and port-0 RX error counters (0x030C, 0x0300).
  void count_frame_error();

  // ---- logical addressing: what the segment's map of the logical address space needs -------
  // One activated FMMU (0x060C bit 0, read and/or write type): logical bits first..last
  // (ETG.1000.4 §6.6: start address x 8 + start bit .. (start + length - 1) x 8 + stop bit).
  struct FmmuRange {
    uint64_t first_bit = 0;
    uint64_t last_bit = 0;
    uint8_t index = 0;  // FMMU n (0x0600 + 16n)
  };
  // The activated FMMUs with a non-empty logical range, in index order; returns how many.
  size_t fmmu_ranges(std::span<FmmuRange, kFmmus> out) const;
  // A counter kept by whoever maps the logical space of many ESCs (Segment): incremented
  // whenever this ESC's FMMU set may have changed (a write to 0x0600-0x06FF, an ESC reset).
  // nullptr (the default): nobody listens.
  void set_fmmu_generation(uint32_t* counter) { fmmu_generation_ = counter; }

  // ---- timers: SYNC0/SYNC1 and the process-data watchdog -----------------------------------
  // Fires every SYNC event due at `now_ns` (clock time base) and expires the process-data
  // watchdog if its deadline passed. A SYNC unit that fell behind by several cycles fires
  // once for the latest due pulse (a µC that missed interrupts sees one).
  void service(uint64_t now_ns);
  // Clock time of the next SYNC event or watchdog deadline; UINT64_MAX when none is pending.
  uint64_t next_event_ns() const;
  // A next-event bound kept by whoever schedules the timers of many ESCs (Segment): whenever
  // this ESC arms or moves a timer (SYNC activation, DC offset or drift correction, watchdog
  // trigger) *bound is lowered to next_event_ns() if that is earlier. It is never raised
  // here: a cancelled or later timer leaves an early bound, which costs the scheduler one
  // look too many, never a late event. nullptr (the default): nobody listens.
  void set_next_event_bound(uint64_t* bound) { next_event_bound_ = bound; }
  // Clock time of the next SYNC0/SYNC1 event; UINT64_MAX when that unit is not running.
  uint64_t next_sync_event_ns() const;
  // Raises a SYNC event now: SYNC status 0x098E/0x098F and AL event bits 2/3; the pulse's
  // system time is what 0x0990 (SYNC0) / 0x0998 (SYNC1) show. `which` is 0 or 1.
  void fire_sync(int which, uint64_t system_time_ns);

  // ---- PDI: the microcontroller's side (ETG.1000.4 §6; ESC datasheet "PDI access") --------
  // Register and process-RAM access with the ESC's PDI-side rules: PDI-writable registers
  // only (AL status and code, AL event mask, SM PDI control, user RAM), SyncManager buffers
  // with their hand-over (see esc/pdi.cpp). Accesses past 0xFFFF are cut at the end.
  void pdi_read(uint16_t address, uint8_t* dst, uint16_t len) {
    // The registers after AL control up to the watchdog status clear no event when read
    // (pdi_registers_read): below every SyncManager buffer, such a read is a copy. Among them
    // the AL event request 0x0220, which a firmware reads on every interrupt (ETG.1000.4 §6.5).
    const uint32_t end = static_cast<uint32_t>(address) + len;
    if (address >= reg::kAlControl + 2 && end <= reg::kWatchdogStatusProcessData &&
        end <= sm_first_byte_) {
      base::copy_bytes(dst, &mem_[address], len);
      return;
    }
    pdi_read_access(address, dst, len);
  }
  void pdi_write(uint16_t address, const uint8_t* src, uint16_t len);
  // One whole SyncManager buffer in one PDI access (SM `sm`, `len` bytes at `address`, its
  // start): what pdi_read/pdi_write of those bytes do - the first byte opens the buffer, the
  // last completes it (ETG.1000.4 §6.7.1/§6.7.2) - without looking for the SyncManager. When
  // SM `sm` is not enabled with exactly that buffer, or shares bytes with another enabled SM,
  // it is a plain pdi_read/pdi_write.
  void pdi_read_buffer(uint8_t sm, uint16_t address, uint8_t* dst, uint16_t len) {
    // The whole buffer of an SM alone in its bytes, in process RAM (no register side effects):
    // the same effects as the byte-wise access, found without the search.
    if (sm < kSyncManagers && whole_sm_buffer(sm, address, len)) {
      sm_read_buffer<false>(sm, dst);
    } else {
      pdi_read(address, dst, len);
    }
  }
  void pdi_write_buffer(uint8_t sm, uint16_t address, const uint8_t* src, uint16_t len) {
    if (sm < kSyncManagers && whole_sm_buffer(sm, address, len)) {
      sm_write_buffer<false>(sm, src);
    } else {
      pdi_write(address, src, len);
    }
  }
  // The IRQ output: AL event request 0x0220 & AL event mask 0x0204.
  bool pdi_irq() const;
  // The ESC was reset (power-on or 'R','E','S' to 0x0040) since the last call: the reset
  // output that restarts the microcontroller behind it (ESC datasheet 0x0040).
  bool take_reset();
  bool reset_pending() const { return reset_signal_; }

  // ---- port wiring (set by Segment) ----------------------------------------------------------
  // Whether a cable with a live partner is on port 1 (port 0 always has the master side).
  void set_port1_link(bool link);
  // Whether frames leave through port 1 to the next slave: link present and the loop not
  // closed by DL control 0x0101 (ETG.1000.4 §6.3.1: 11b = closed, 01b = auto-close).
  bool forwards_to_port1() const { return forwards_port1_; }

  // ---- observers (tests, CLI, the link) -------------------------------------------------------
  // AL status 0x0130 as the firmware last wrote it (state bits 3..0, error flag bit 4).
  uint8_t al_status() const { return mem_[0x0130]; }
  bool al_error() const;
  uint16_t al_status_code() const;
  uint16_t station_address() const;
  uint64_t local_time(uint64_t clock_ns) const;
  uint64_t system_time(uint64_t clock_ns) const;
  // Raw view of the address space, no side effects (what a PDI read of the registers shows).
  std::span<const uint8_t, kMemorySize> memory() const { return mem_.view(); }
  uint8_t read8(uint16_t address) const { return mem_[address]; }
  uint16_t read16(uint16_t address) const;
  uint32_t read32(uint16_t address) const;
  uint64_t read64(uint16_t address) const;
  // The SII EEPROM as the ESC holds it (initial image plus master and PDI writes), padded with
  // 0xFF to the size declared in word 0x3E.
  std::span<const uint8_t> eeprom() const { return sii_; }

 private:
  struct SmState {
    uint16_t start = 0;
    uint16_t length = 0;
    uint8_t control = 0;
    bool enabled = false;     // ECAT activate bit (0x0806 bit 0) and a non-zero length
    bool active = false;      // enabled and not deactivated by the PDI (0x0807 bit 0)
    uint8_t next_buffer = 0;  // buffered mode: buffer index that receives the next write
    // Status bits that make its ECAT event (0x0210) and AL event (0x0220) pending; 0 when
    // that event is off (sync_manager.cpp, from control and enabled).
    uint8_t ecat_event_status = 0;
    uint8_t al_event_status = 0;
  };
  struct FmmuState {
    uint32_t logical_start = 0;
    uint16_t length = 0;
    uint8_t logical_start_bit = 0;
    uint8_t logical_stop_bit = 7;
    uint16_t physical_start = 0;
    uint8_t physical_start_bit = 0;
    uint8_t type = 0;  // bit 0 read, bit 1 write
    // Derived when the FMMU is (re)loaded (ETG.1000.4 §6.6): logical bits first_bit..last_bit
    // (maps = false when the range is empty) and physical bit = logical bit + shift.
    bool maps = false;
    uint64_t first_bit = 0;
    uint64_t last_bit = 0;
    int64_t shift = 0;
  };

  // esc.cpp: reset, datagram dispatch, physical access.
  void power_on_reset();
  bool addressed_by_station(uint16_t adp) const;
  // The system time 0x0910 alone, 4 or 8 bytes, with no SyncManager over it: the access every
  // DC master makes every cycle (FRMW/ARMW, ETG.1000.4 §9). For these bytes the register rules
  // come down to one read and one compare (0x0910 has no ECAT-writable bit, raises no event
  // and shares its range with no other register), so physical_read/physical_write serve them
  // with read_system_time/write_system_time instead of the mask table and the event rewrite.
  bool is_system_time_access(uint16_t address, uint16_t len) const {
    return address == reg::kDcSystemTime && (len == 4 || len == 8) &&
           static_cast<uint32_t>(reg::kDcSystemTime) + len <= sm_first_byte_;
  }
  // One side of a physical datagram; false when the register or SyncManager rules refuse it
  // (no WKC). merge_or: BRD/BRW OR the memory into the datagram. The system time 0x0910 alone
  // has its own read and write (is_system_time_access), every other range the generic rules.
  bool physical_read(uint16_t address, uint8_t* dst, uint16_t len, bool merge_or) {
    if (!is_system_time_access(address, len)) return generic_read(address, dst, len, merge_or);
    read_system_time(dst, len, merge_or);
    return true;
  }
  bool physical_write(uint16_t address, const uint8_t* src, uint16_t len) {
    if (!is_system_time_access(address, len)) return generic_write(address, src, len);
    return write_system_time(src, len);
  }
  // The generic rules and the read-write commands (APRW/FPRW/BRW: both sides, the read first,
  // their working counter) stay out of line: process_physical is then a dispatcher without a
  // stack frame, and the FRMW 0x0910 every DC cycle passes through it in a few instructions.
  [[gnu::noinline]] bool generic_read(uint16_t address, uint8_t* dst, uint16_t len, bool merge_or);
  [[gnu::noinline]] bool generic_write(uint16_t address, const uint8_t* src, uint16_t len);
  [[gnu::noinline]] uint8_t physical_read_write(uint16_t address, uint8_t* data, uint16_t len,
                                                bool merge_or);
  // A physical datagram where it acts (where it addresses; ARMW/FRMW everywhere) through the
  // register and SyncManager rules; returns its working counter.
  uint8_t process_physical(uint8_t command, uint16_t address, uint8_t* data, uint16_t len,
                           bool addressed);
  // register_map.cpp: write masks and side effects of register accesses.
  void write_registers(uint16_t address, const uint8_t* src, uint16_t len);
  void after_register_write(uint16_t address, const uint8_t* src, uint16_t len);
  void dc_registers_written(uint16_t address, const uint8_t* src, uint16_t len);
  void before_register_read(uint16_t address, uint16_t len);
  void after_register_read(uint16_t address, uint16_t len);
  // Registers a cyclic frame consults but a master writes only while it configures the slave
  // are derived when they are written and at reset, so the frame reads them from the ESC
  // object, not from their register lines.
  // write_protection.cpp: register and ESC write protection (0x0021/0x0031 bit 0).
  void derive_write_protection();
  // This check runs on every write.
  bool write_protection_active() const {
    return protection_ != 0 && (((protection_ & kRegisterProtection) && !register_write_enabled_) ||
                                ((protection_ & kEscProtection) && !esc_write_enabled_));
  }
  bool write_allowed(uint32_t address) const;
  void write_enables_written(uint16_t address, const uint8_t* src, uint16_t len);
  bool protected_write(uint16_t address, const uint8_t* src, uint16_t len);
  // fmmu.cpp: logical addressing.
  uint8_t process_logical(uint8_t command, uint32_t address, uint8_t* data, uint16_t len,
                          uint16_t fmmus);
  // The bit-wise walk process_logical takes when process_whole_fmmus does not apply.
  uint8_t walk_fmmus(Command cmd, uint8_t usable, uint32_t address, uint8_t* data, uint16_t len,
                     uint16_t fmmus);
  void or_irq(uint8_t* datagram) const;
  // The datagram leaves this ESC: `wkc` added to its working counter (after `data_len` data
  // bytes), its IRQ field ORed with this ESC's masked events (ETG.1000.4 §5.4).
  void leave_datagram(uint8_t* datagram, uint16_t data_len, unsigned wkc) const {
    if (wkc != 0) {
      uint8_t* counter = datagram + kDatagramHeaderSize + data_len;
      le::put16(counter, static_cast<uint16_t>(le::get16(counter) + wkc));
    }
    or_irq(datagram);
  }
  // One FMMU intersected with one logical datagram, computed once per datagram: logical bits
  // lo..hi inside both, the bit shift onto physical memory and the physical bytes touched.
  // No default member values: process_logical keeps 2 x 16 of them on the stack per datagram
  // and fills only those an FMMU meets (intersect_fmmu sets every field when it succeeds).
  struct FmmuSpan {
    uint64_t lo;
    uint64_t hi;
    int64_t shift;  // physical bit = logical bit + shift
    uint32_t phys_first;
    uint32_t phys_len;
    int fmmu;  // FMMU n (set by process_logical)
  };
  // Intersects FMMU `f` with the datagram's logical bits dg_lo..dg_hi; false when they do not
  // meet or the physical side would run past the 64 KiB address space.
  static bool intersect_fmmu(const FmmuState& f, uint64_t dg_lo, uint64_t dg_hi, FmmuSpan& out);
  // The enabled SMs span s meets: known per FMMU (refresh_fmmu_meetings) or looked up.
  uint16_t span_meeting(const FmmuSpan& s) const {
    if ((fmmu_meeting_known_ & (1u << s.fmmu)) != 0) return fmmu_meeting_[s.fmmu];
    return sm_meeting(s.phys_first, s.phys_first + s.phys_len);
  }
  bool fmmu_read(const FmmuSpan& s, uint64_t datagram_bit0, uint8_t* data);
  bool fmmu_write(const FmmuSpan& s, uint64_t datagram_bit0, const uint8_t* data);
  void reload_fmmu(int index);
  // The enabled SyncManagers an access through FMMU n meets, when that is the same for every
  // part of its physical range: none, or one SM that shares no byte with another and holds the
  // whole range. Recomputed whenever an FMMU or SM is (re)loaded; fmmu_meeting_known_ bit n
  // says fmmu_meeting_[n] holds it (else the access looks the SMs up, sm_meeting).
  void refresh_fmmu_meetings();
  // The cyclic process data: bit n of fmmu_whole_mask_ says FMMU n maps whole bytes of
  // process RAM at the same bit positions (start bits 0, stop bit 7; ETG.1000.4 §6.6) onto
  // exactly the buffer of one enabled SM that shares no byte with another, or onto bytes no SM
  // meets (kept with the meetings). A logical datagram that covers every such FMMU it meets
  // completely is served by process_whole_fmmus: per FMMU one copy and one whole-buffer
  // hand-over, in the order and with the effects of the bit-wise walk. Returns the working
  // counter, or -1 when an FMMU the datagram meets is not whole or only partly covered.
  int process_whole_fmmus(Command cmd, uint8_t usable, uint32_t address, uint8_t* data,
                          uint16_t len, uint16_t fmmus);
  // One side of a logical datagram, its reads or its writes: the FMMUs it goes through (bit n
  // = FMMU n) and the datagram bytes they cover, [first, end) relative to its data. LRW reads
  // the old memory into the datagram while writing the incoming data (ETG.1000.4 §5.4.3):
  // where the reads' bytes meet the writes', the incoming bytes are kept aside first.
  struct FmmuSide {
    uint16_t fmmus = 0;
    uint32_t first = UINT32_MAX;
    uint32_t end = 0;
    void add(int fmmu, uint32_t part_first, uint32_t part_end) {
      fmmus = static_cast<uint16_t>(fmmus | (1u << fmmu));
      first = std::min(first, part_first);
      end = std::max(end, part_end);
    }
    bool meets(const FmmuSide& other) const { return first < other.end && other.first < end; }
  };
  // Copies the incoming bytes [first, end) the writes take aside (datagram_scratch(), at the
  // same offsets) and returns where the writes find them.
  const uint8_t* keep_incoming(const uint8_t* data, uint32_t first, uint32_t end);
  // Where RW commands and meeting FMMUs keep a datagram's incoming bytes while the old memory
  // is read into it: one buffer per thread, not per ESC (2 KiB each), since an ESC needs it
  // only while it serves one datagram and a segment's ESCs serve it one after the other.
  // Holds any datagram of a frame (ETG.1000.4 §5.4: at most 1,486 data bytes).
  static constexpr size_t kDatagramScratch = 2048;
  static uint8_t* datagram_scratch();
  // What process_whole_fmmus works out for a datagram from the FMMU configuration alone, kept
  // for the last one (the cyclic frame repeats it) until an FMMU or SM is (re)loaded: with each
  // FMMU's place in the datagram, so serving it reads no FMMU state. A datagram's bytes fit
  // 16 bits (its length field, ETG.1000.4 §5.4).
  struct WholePlan {
    uint32_t address = 0;
    uint16_t len = 0;
    uint16_t fmmus = 0;
    uint8_t usable = 0;
    bool valid = false;
    bool whole = false;   // every FMMU the datagram meets is whole and completely covered
    uint16_t reads = 0;   // the FMMUs read through (bit n = FMMU n)
    uint16_t writes = 0;  // ... and written through
    // The datagram bytes the writes take, [first, end), kept aside when the reads fill some of
    // them; empty otherwise.
    uint16_t incoming_first = 0;
    uint16_t incoming_end = 0;
    // FMMU n's first byte in the datagram's data (its logical start - the datagram's address),
    // for n in reads | writes.
    std::array<uint16_t, kFmmus> offset{};
    // The cyclic exchange (sm_exchange_buffers): an LRW through one FMMU reading the input SM
    // the PDI fills and one writing the output SM the master fills, both active and buffered,
    // at separate places in the datagram. Valid as long as the plan is: any FMMU or SM reload
    // (the only way `active` or the control byte changes) discards it.
    bool exchange = false;
    bool exchange_watchdog = false;  // the output SM's control enables the watchdog trigger
    uint8_t input_sm = 0;
    uint8_t output_sm = 0;
    uint16_t input_offset = 0;
    uint16_t output_offset = 0;
  };
  void plan_whole_fmmus(WholePlan& p, uint8_t usable, uint32_t address, uint16_t len,
                        uint16_t fmmus);
  // The exchange part of plan p, once the rest is made.
  void plan_exchange(WholePlan& p, uint8_t usable);
  // The planned exchange of the last plan used, for datagram data `data`; its WKC.
  int exchange_whole(uint8_t* data);
  void forget_whole_plans() {
    whole_plans_[0].valid = false;
    whole_plans_[1].valid = false;
  }
  // process_logical_datagram: the planned exchange for the whole datagram (working counter,
  // IRQ field; sync_manager.cpp), and every other logical datagram (fmmu.cpp).
  void exchange_datagram(uint8_t* datagram, uint16_t data_len);
  void logical_datagram(uint8_t* datagram, uint16_t data_len, uint16_t fmmus);
  bool whole_fmmu_read(int index, uint8_t* dst);
  bool whole_fmmu_write(int index, const uint8_t* src);
  // sync_manager.cpp: buffer semantics.
  void reload_sm(int index);
  bool sm_allows_read(uint16_t address, uint16_t len);
  void sm_after_read(uint16_t address, uint16_t len);
  bool sm_allows_write(uint16_t address, uint16_t len);
  void sm_after_write(uint16_t address, uint16_t len);
  // The same for an access whose enabled SyncManagers are already known (`meeting`, bit n =
  // SM n, from sm_meeting): one lookup serves the check and the hand-over.
  uint16_t sm_meeting(uint32_t address, uint32_t end) const;
  bool sm_allows_read(uint16_t meeting);
  void sm_after_read(uint16_t meeting, uint16_t address, uint16_t len);
  bool sm_allows_write(uint16_t meeting);
  void sm_after_write(uint16_t meeting, uint16_t address, uint16_t len);
  // An access to bytes [address, end) of SM n's buffer by the side that fills it (`filler`:
  // the master for an SM it writes, the PDI for one it reads) or by the side that drains it:
  // opens the buffer on its first byte, completes it on its last (status 0x0805+8n, events).
  void sm_buffer_access(int index, uint32_t address, uint32_t end, bool filler);
  // The same with the access's place in the buffer known: `first` = it holds the buffer's first
  // byte, `last` its last byte.
  void sm_hand_over(int index, bool first, bool last, bool filler);
  // One access that is exactly SM n's whole buffer (in process RAM), by the master (through
  // an FMMU) or by the PDI: what the checks (sm_allows_read/sm_allows_write for the master,
  // pdi_buffer_write's for the PDI), the copy and the hand-over of the first and the last byte
  // do for it. False when the access is refused (the master gets no WKC). One instance per
  // side (sync_manager.cpp): each side's checks fold away.
  template <bool by_master>
  bool sm_read_buffer(int index, uint8_t* dst);
  template <bool by_master>
  bool sm_write_buffer(int index, const uint8_t* src);
  // The master's cyclic exchange through two whole buffered SMs in one LRW (ETG.1000.4
  // §6.7.2): sm_read_buffer<true>(input, dst), then sm_write_buffer<true>(output, src) unless
  // `write` is false (write protection refused it), with the checks process_whole_fmmus' plan
  // made once left out: both SMs active and buffered, the PDI filling `input`, the master
  // `output`. `watchdog`: output's control enables the process-data watchdog trigger. Returns
  // the LRW's working counter (ETG.1000.4 §5.4.4): 1 for the read, 2 more for the write.
  int sm_exchange_buffers(int input, uint8_t* dst, int output, const uint8_t* src, bool write,
                          bool watchdog);
  // Whether bytes [address, address + len) are SM n's whole buffer, in process RAM, shared
  // with no other enabled SM.
  bool whole_sm_buffer(int index, uint16_t address, uint16_t len) const {
    return (sm_alone_mask_ & (1u << index)) != 0 && sm_[index].start == address &&
           sm_[index].length == len && address >= reg::kProcessRam;
  }
  // Whether the side that fills SM n's buffer may write it now (active, a mailbox not full).
  bool sm_takes_write(int index) const;
  uint8_t& sm_status(int index) { return mem_[reg::sm::base(index) + reg::kSmStatusOffset]; }
  // Calls f(n) for every enabled SyncManager n whose buffer meets bytes [address, end).
  template <class F>
  void for_each_sm_meeting(uint32_t address, uint32_t end, F&& f) const {
    if (end <= sm_first_byte_) return;  // e.g. a register access
    for (uint16_t mask = sm_enabled_mask_; mask != 0; mask &= static_cast<uint16_t>(mask - 1)) {
      const int n = __builtin_ctz(mask);
      const SmState& s = sm_[n];
      if (address < static_cast<uint32_t>(s.start) + s.length && s.start < end) f(n);
    }
  }
  // ECAT event request 0x0210 bit 4+n and AL event request 0x0220 bit 8+n from SM n's status.
  void update_sm_events(int index);
  // pdi.cpp: the microcontroller's accesses.
  bool pdi_buffer_write(uint16_t address, const uint8_t* src, uint16_t len);
  void pdi_buffer_read_done(uint16_t address, uint16_t len);
  void pdi_registers_written(uint16_t address, const uint8_t* src, uint16_t len, bool sii_owned);
  // pdi_read for every other access: register side effects and SyncManager buffers.
  void pdi_read_access(uint16_t address, uint8_t* dst, uint16_t len);
  void pdi_registers_read(uint16_t address, uint16_t len);
  // sii.cpp: EEPROM interface.
  void sii_load_image();
  void sii_reload_config_area();
  void sii_command(uint8_t control_lo, uint8_t command, bool control_lo_written);
  bool sii_assigned_to_pdi() const;
  uint8_t sii_pdi_write_mask(uint16_t address, bool sii_owned) const;
  // distributed_clock.cpp
  void dc_latch_receive_times();
  void dc_system_time_written(uint16_t address, const uint8_t* src, uint16_t len);
  // ESC datasheet 0x0910 read: the system time when the frame passed, latched into the
  // register and copied (ORed for BRD/BRW) into `dst`.
  void read_system_time(uint8_t* dst, uint16_t len, bool merge_or);
  // ESC datasheet 0x0910 write, through register write protection; false when discarded.
  bool write_system_time(const uint8_t* src, uint16_t len);
  // "Write: compare with local copy": `received` (4 bytes: the low 32 bits, 8 bytes: all 64)
  // plus the delay 0x0928 against the local system time; the difference goes to 0x092C and
  // drives the control loop.
  void dc_compare_system_time(const uint8_t* received, uint16_t len);
  void dc_activation_written();
  void dc_prepare_system_time_read();
  uint64_t clock_of_system_time(uint64_t system_time) const;
  // watchdog.cpp
  // The process-data watchdog's period from divider 0x0400 and time 0x0420 (ESC datasheet).
  void derive_watchdog_period();
  void watchdog_trigger(uint64_t now_ns);
  void watchdog_expired();
  // A timer was armed or moved: lowers the next-event bound (set_next_event_bound).
  void timers_changed();

  // What every cyclic frame and the firmware's process-data round touch comes first, on as few
  // cache lines as it fits (at 199 slaves each line is a miss again every frame), from a line
  // boundary: the memory, the pass times, the watchdog, the masks and flags of the datagram and
  // PDI paths (one line), the whole-buffer plan and the FMMUs' SyncManagers (the next), then the
  // SyncManagers (SM0-SM3 on the third line). The FMMUs, the next-event bound and the
  // configuration-time state follow.
  alignas(base::kCacheLine) EscMemory mem_;  // registers and process RAM, resident as far as used
  PassTimes pass_{};
  uint64_t watchdog_period_ns_ = 0;  // derive_watchdog_period; 0: disabled
  uint64_t watchdog_deadline_ = 0;   // clock time, armed by SM2 writes with trigger enabled
  uint32_t sm_first_byte_ = reg::kAddressSpace;  // lowest start of an enabled SM's buffer
  uint16_t sm_enabled_mask_ = 0;
  uint16_t sm_alone_mask_ = 0;     // bit n: SM n enabled, no other enabled SM shares a byte
  uint16_t fmmu_active_mask_ = 0;  // bit n: FMMU n activated with a read or write type
  uint16_t fmmu_meeting_known_ = 0;
  uint16_t fmmu_whole_mask_ = 0;
  bool port1_link_ = false;
  // Port 1 forwards (forwards_to_port1), derived in set_port1_link from the link and DL
  // control 0x0101.
  bool forwards_port1_ = false;
  // derive_write_protection: 0x0021 bit 0 (kRegisterProtection), 0x0031 bit 0 (kEscProtection).
  static constexpr uint8_t kRegisterProtection = 0x01;
  static constexpr uint8_t kEscProtection = 0x02;
  uint8_t protection_ = 0;
  bool register_write_enabled_ = false;  // 0x0020 bit 0 written in the current frame
  bool esc_write_enabled_ = false;       // 0x0030 bit 0 written in the current frame
  bool reset_signal_ = true;             // raised by every reset until take_reset()
  bool watchdog_armed_ = false;          // the process-data watchdog's deadline is set
  bool watchdog_running_ = true;         // 0x0440 bit 0: not expired
  // Two plans: a master whose image takes two datagrams (inputs in one, outputs in the other,
  // as ethercrab and SOEM cut an image larger than one frame) sends both to each ESC every
  // cycle, and one kept plan would be made again for each. whole_plans_[last_plan_] is the one
  // the last logical datagram used; a new plan replaces the other.
  std::array<WholePlan, 2> whole_plans_{};
  uint8_t last_plan_ = 0;
  std::array<uint16_t, kFmmus> fmmu_meeting_{};
  std::array<SmState, kSyncManagers> sm_{};
  std::array<FmmuState, kFmmus> fmmu_{};
  uint64_t* next_event_bound_ = nullptr;

  SiiEeprom& eeprom_;
  const Clock& clock_;
  EscOptions options_;
  std::vector<uint8_t> sii_;
  std::array<uint8_t, kSyncManagers> activate_seen_{};  // 0x0806+8n at the last reload
  uint32_t* fmmu_generation_ = nullptr;
  uint8_t reset_sequence_ = 0;  // 0x0040 'R','E','S' progress

  // Distributed clocks: local(t) = t + local_offset_; system = local + 0x0920.
  uint64_t local_offset_ = 0;
  bool sync0_running_ = false;
  bool sync1_running_ = false;
  uint64_t next_sync0_ = 0;  // system time
  uint64_t next_sync1_ = 0;  // system time
  uint64_t sync0_count_ = 0;
};

}  // namespace rackcat::ecat
