#include "ecat/segment.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include "base/little_endian.hpp"
#include "base/round_time.hpp"

namespace rackcat::ecat {

Segment::Slave::Slave(Application& app, const Clock& clock, const EscOptions& options,
                      PdiAccess pdi)
    : app_(app),
      eeprom_(app),
      esc_(eeprom_, clock, options),
      pdi_(esc_),
      firmware_(make_pdi(pdi), app) {
  esc_.take_reset();  // the firmware has just started with the chip
  firmware_.set_observer(&event_log_);
}

PdiPort& Segment::Slave::make_pdi(PdiAccess access) {
  if (access == PdiAccess::Direct) return pdi_;
  lan9252_ = std::make_unique<Lan9252Model>(esc_);
  lan9252_pdi_ = std::make_unique<Lan9252Pdi>(*lan9252_);
  if (!lan9252_pdi_->start()) throw std::runtime_error("LAN9252 model does not answer");
  return *lan9252_pdi_;
}

Segment::Segment(std::vector<Application*> applications, const Clock& clock, SegmentOptions options)
    : clock_(clock), options_(options), logical_map_(applications.size(), Esc::kFmmus) {
  if (applications.empty()) throw std::invalid_argument("a segment needs at least one slave");
  const size_t n = applications.size();
  slaves_.reserve(n);
  for (size_t k = 0; k < n; ++k) {
    if (applications[k] == nullptr) throw std::invalid_argument("null application in segment");
    EscOptions esc = options_.esc;
    esc.power_on_local_time_ns = esc.power_on_local_time_ns + k * options_.power_on_spacing_ns;
    slaves_.push_back(std::make_unique<Slave>(*applications[k], clock_, esc, options_.pdi));
    slaves_[k]->esc().set_port1_link(k + 1 < n);
    slaves_[k]->esc().set_next_event_bound(&next_event_bound_);
    slaves_[k]->esc().set_fmmu_generation(&fmmu_generation_);
  }
  // Arrival at port 0 of slave k, and the time the frame takes from entering slave k at port 0
  // to leaving it at port 0 again (through everything behind it).
  offsets_.resize(n);
  const uint64_t hop = options_.forward_delay_ns + options_.cable_delay_ns;
  std::vector<uint64_t> loop(n);
  loop[n - 1] = options_.forward_delay_ns;  // last slave: processing unit, then port 0 out
  for (size_t k = n - 1; k-- > 0;) {
    loop[k] = options_.forward_delay_ns + 2ull * options_.cable_delay_ns + loop[k + 1] +
              options_.return_delay_ns;
  }
  for (size_t k = 0; k < n; ++k) {
    offsets_[k].port0_ns = k * hop;
    offsets_[k].port1_ns = k + 1 < n
                               ? offsets_[k].port0_ns + hop + loop[k + 1] + options_.cable_delay_ns
                               : offsets_[k].port0_ns;
  }
}

size_t Segment::process(std::span<uint8_t> frame) {
  parse_frame(frame, layout_);
  if (layout_.kind == FrameLayout::Kind::NotEtherCat) return 0;
  // The ESC marks frames it has processed: bit 1 of the first source-MAC byte (locally
  // administered), so a master can tell its own frame from the one the line returns.
  frame[6] |= 0x02;
  if (layout_.kind == FrameLayout::Kind::OtherType) return frame.size();
  if (!deferred_firmware_) after_frame();
  const uint64_t t0 = clock_.now_ns();
  if (t0 >= next_event_bound_) service_at(t0);
  uint8_t* base = frame.data();
  const bool mapped = resolve_logical(base);
  const size_t passed =
      mapped && layout_.count == 1 && targets_[0] != nullptr && !layout_.malformed
          ? pass_cyclic_datagram(base + layout_.offset[0], layout_.length[0], *targets_[0], t0)
          : pass_datagrams(base, mapped, t0);
  // A new round over every slave the frame passed (and those an unfinished round still
  // covers), starting where the last slice stopped.
  round_span_ = round_left_ != 0 ? std::max(round_span_, passed) : passed;
  round_left_ = round_span_;
  if (cursor_ >= round_span_) cursor_ = 0;
  return frame.size();
}

size_t Segment::pass_datagrams(uint8_t* base, bool mapped, uint64_t t0) {
  for (size_t k = 0; k < slaves_.size(); ++k) {
    Slave& slave = *slaves_[k];
    Esc& esc = slave.esc();
    if (k + 1 < slaves_.size()) slaves_[k + 1]->esc().prefetch();
    esc.begin_frame({t0 + offsets_[k].port0_ns, t0 + offsets_[k].port1_ns});
    for (size_t d = 0; d < layout_.count; ++d) {
      uint8_t* datagram = base + layout_.offset[d];
      if (mapped && targets_[d] != nullptr) {
        // Targets are in line order, one per slave: the next one is this slave or a later one.
        const std::vector<LogicalMap::Target>& t = *targets_[d];
        uint32_t& next = next_target_[d];
        if (next < t.size() && t[next].slave == k) {
          esc.process_logical_datagram(datagram, layout_.length[d], t[next].fmmus);
          ++next;
        } else {
          esc.pass_datagram(datagram);
        }
      } else {
        esc.process_datagram(datagram, layout_.length[d]);
      }
      // A datagram that changed an FMMU (0x0600-0x06FF, an ESC reset) makes the map stale:
      // the rest of this frame is handled by every ESC's own FMMU walk.
      if (mapped && fmmu_generation_ != map_generation_) mapped = false;
    }
    if (layout_.malformed) esc.count_frame_error();
    // The frame has left this ESC: its firmware runs in after_frame(), once the reply is out.
    if (!esc.forwards_to_port1()) return k + 1;  // last slave, or loop closed by DL control
  }
  return slaves_.size();
}

size_t Segment::pass_cyclic_datagram(uint8_t* datagram, uint16_t len,
                                     const std::vector<LogicalMap::Target>& targets, uint64_t t0) {
  // The general loop's steps for a frame of one datagram, with what it looks up per slave and
  // datagram held in locals: the master's cyclic frame costs this per slave on the wire.
  const size_t n = slaves_.size();
  const PassTimes* offsets = offsets_.data();
  const LogicalMap::Target* target = targets.data();
  const LogicalMap::Target* const targets_end = target + targets.size();
  bool mapped = true;
  for (size_t k = 0; k < n; ++k) {
    Esc& esc = slaves_[k]->esc();
    if (k + 1 < n) slaves_[k + 1]->esc().prefetch();
    esc.begin_frame({t0 + offsets[k].port0_ns, t0 + offsets[k].port1_ns});
    if (!mapped) {
      esc.process_datagram(datagram, len);
    } else if (target != targets_end && target->slave == k) {
      esc.process_logical_datagram(datagram, len, target->fmmus);
      ++target;
      // An FMMU written through an FMMU (mapped onto 0x0600-0x06FF) makes the map stale: the
      // rest of the line walks its own FMMUs.
      if (fmmu_generation_ != map_generation_) mapped = false;
    } else {
      esc.pass_datagram(datagram);
    }
    if (!esc.forwards_to_port1()) return k + 1;  // last slave, or loop closed by DL control
  }
  return n;
}

bool Segment::resolve_logical(const uint8_t* base) {
  bool any = false;
  size_t resolved = 0;
  for (size_t d = 0; d < layout_.count; ++d) {
    const uint8_t* datagram = base + layout_.offset[d];
    const auto cmd = static_cast<Command>(datagram[0]);
    targets_[d] = nullptr;
    if (cmd != Command::Lrd && cmd != Command::Lwr && cmd != Command::Lrw) continue;
    if (!any) {
      if (map_generation_ != fmmu_generation_) rebuild_logical_map();
      logical_map_.begin_frame();
      any = true;
    }
    // More distinct logical datagrams than the map keeps per frame: the rest walk the FMMUs.
    if (resolved == LogicalMap::kCachedRanges) continue;
    targets_[d] = logical_map_.resolve(le::get32(datagram + 2), layout_.length[d]);
    next_target_[d] = 0;
    if (targets_[d] != nullptr) ++resolved;
  }
  return any;
}

void Segment::rebuild_logical_map() {
  logical_map_.clear();
  std::array<Esc::FmmuRange, Esc::kFmmus> ranges{};
  for (size_t k = 0; k < slaves_.size(); ++k) {
    const size_t n = slaves_[k]->esc().fmmu_ranges(ranges);
    for (size_t i = 0; i < n; ++i) {
      logical_map_.add(static_cast<uint32_t>(k), ranges[i].first_bit, ranges[i].last_bit,
                       ranges[i].index);
    }
  }
  logical_map_.finish();
  map_generation_ = fmmu_generation_;
}

void Segment::after_frame() {
  // One clock read for the whole round (base/round_time.hpp).
  const base::RoundTime::Scope round;
  while (round_left_ != 0) {
    const size_t k = cursor_;
    cursor_ = k + 1 == round_span_ ? 0 : k + 1;
    --round_left_;
    if (round_left_ != 0) slaves_[cursor_]->prefetch_firmware();
    slaves_[k]->run_firmware_if_due();
  }
}

bool Segment::run_firmware_slice(uint64_t budget_ns) {
  if (round_left_ == 0) return false;
  const base::RoundTime::Scope round;
  const uint64_t until = clock_.now_ns() + budget_ns;
  do {
    const size_t k = cursor_;
    cursor_ = k + 1 == round_span_ ? 0 : k + 1;
    --round_left_;
    slaves_[k]->run_firmware_if_due();
  } while (round_left_ != 0 && clock_.now_ns() < until);
  return round_left_ != 0;
}

void Segment::service_slave(Slave& s, uint64_t now) {
  // SYNC pulses and the watchdog expiry raise AL events (0x0220); the IRQ line wakes the
  // firmware for them.
  s.esc().service(now);
  if (s.esc().pdi_irq()) s.run_firmware();
}

void Segment::service() {
  service_at(clock_.now_ns());
}

void Segment::service_at(uint64_t now) {
  uint64_t next = std::numeric_limits<uint64_t>::max();
  for (auto& s : slaves_) {
    service_slave(*s, now);
    next = std::min(next, s->esc().next_event_ns());
  }
  next_event_bound_ = next;
}

uint64_t Segment::next_event_ns() const {
  uint64_t next = std::numeric_limits<uint64_t>::max();
  for (const auto& s : slaves_) next = std::min(next, s->esc().next_event_ns());
  return next;
}

uint64_t Segment::next_sync_event_ns() const {
  uint64_t next = std::numeric_limits<uint64_t>::max();
  for (const auto& s : slaves_) next = std::min(next, s->esc().next_sync_event_ns());
  return next;
}

}  // namespace rackcat::ecat
