// Digital slot cards: inputs (guide Table 3 0x9000/0xC000/0xD000, Table 5 DINx8 and the x8
// oversampled idents), outputs (0x3000/0x5000/0x7000/0xA000/0xB000/0xE000) and the E84 DIO
// card (0x4000). Process-data objects per Appendix A: 0x6nn0/1/5/6/B/C, 0x7nn0/1/B; safe
// states 0x4nn0 (16 channels, UINT) and 0x4nn1 (8 or 4 channels, USINT), guide Tables 7-8.
#include <fmt/format.h>
#include <bit>
#include <cstring>
#include <stdexcept>

#include "coe/entry_slot.hpp"
#include "modules/cards/drivers.hpp"
#include "modules/cards/safe_state.hpp"
#include "modules/cards/substitute.hpp"

namespace rackcat::modules {

coe::Object& require_object(coe::ObjectDictionary& od, uint16_t index, const mdp::Module& m) {
  coe::Object* o = od.find(index);
  if (o == nullptr) {
    throw std::runtime_error(
        fmt::format("module {} ({} in RIM {} slot {}): object 0x{:04X} missing", m.number,
                    m.card->name, m.rim, m.slot, index));
  }
  return *o;
}

float read_real32(const coe::Object& o, uint8_t subindex) {
  return std::bit_cast<float>(static_cast<uint32_t>(o.get_u(subindex)));
}

namespace {

bool level(double v) {
  return v >= 0.5;
}

// Digital inputs, 4/8/16 channels, once or eight times per cycle.
class DigitalInputDriver final : public CardDriver {
 public:
  DigitalInputDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, m.card->channels, 0),
        samples_(m.card->samples),
        inverted_(m.card->signal == mdp::Signal::DigitalInInverted),
        obj_(require_object(od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)),
        word_(obj_, 1) {
    if (samples_ > 1) {
      raw_ = obj_.bytes(1);
      sample_bytes_ = card().channels > 8 ? 2 : 1;
      if (raw_.size() < static_cast<size_t>(samples_) * sample_bytes_)
        throw std::runtime_error(fmt::format("module {}: sample array too small", m.number));
    }
  }

  void write_inputs(double t, double dt) override {
    if (samples_ == 1) {
      const uint32_t word = sample_word(t);
      inputs_code(word);
      word_.set(word);
      return;
    }
    // Sample k of 0..7 at t - dt + (k+1) dt/8: sample 0 is the oldest, 7 is taken now.
    // Channels whose sources cannot change within a cycle are sampled once.
    const bool varies = sources_vary();
    uint32_t word = 0;
    for (unsigned k = 0; k < samples_; ++k) {
      const double ts = t - dt + (k + 1) * dt / samples_;
      if (varies || k == 0) word = sample_word(varies ? ts : t);
      raw_[k * sample_bytes_] = static_cast<uint8_t>(word);
      if (sample_bytes_ == 2) raw_[k * sample_bytes_ + 1] = static_cast<uint8_t>(word >> 8);
      if (k + 1 == samples_) inputs_code(word);
    }
  }

  void clear_inputs() override {
    if (samples_ == 1) {
      obj_.set_u(1, 0);
    } else {
      std::memset(raw_.data(), 0, raw_.size());
    }
    for (auto& in : inputs_) in.code = 0;
    codes_current_ = false;
  }

  const char* input_unit() const override { return "bit"; }
  // Every sample of an affine source is the same: oversampling repeats it (write_inputs).
  bool time_invariant() const override { return sources_affine(); }

 protected:
  void put_input_code(size_t i, uint32_t code) override {
    codes_current_ = false;
    const uint32_t bit = 1u << i;
    if (samples_ == 1) {
      const auto word = static_cast<uint32_t>(obj_.get_u(1));
      word_.set((code & 1u) ? word | bit : word & ~bit);
      return;
    }
    const auto mask = static_cast<uint8_t>(1u << (i % 8));
    for (unsigned k = 0; k < samples_; ++k) {
      uint8_t& b = raw_[k * sample_bytes_ + i / 8];
      b = (code & 1u) ? static_cast<uint8_t>(b | mask) : static_cast<uint8_t>(b & ~mask);
    }
  }

 private:
  uint32_t sample_word(double t) {
    uint32_t word = 0;
    InputChannel* const channels = inputs_.data();
    const size_t n = inputs_.size();
    for (size_t i = 0; i < n; ++i) {
      InputChannel& in = channels[i];
      in.value = sample(i, t);
      // Inverted cards report a low input as 1 (guide Table 3 0x9000).
      if (level(in.value) != inverted_) word |= 1u << i;
    }
    return word;
  }
  void inputs_code(uint32_t word) {
    // The codes hold `word` already unless a substitute value or clear_inputs() changed one
    // since (issue 16: no per-channel stores while the inputs stay the same).
    codes_repeated_ = codes_current_ && word == coded_word_;
    if (codes_repeated_) return;
    for (size_t i = 0; i < inputs_.size(); ++i) inputs_[i].code = (word >> i) & 1u;
    coded_word_ = word;
    codes_current_ = true;
  }

  // Per-cycle fields first (after the base's, issue 16).
  unsigned samples_;
  bool inverted_;
  bool codes_current_ = false;  // the channels' codes hold coded_word_, no code changed since
  uint32_t coded_word_ = 0;     // the word inputs_code() last stored in the channels' codes
  coe::Object& obj_;
  coe::EntrySlot word_;  // DINx16 / DINx8 (DINx4 is a BIT4: set_u fallback)
  std::span<uint8_t> raw_;
  unsigned sample_bytes_ = 1;
};

// Reads the digital output word of 0x7nnX and applies 0x4nn0/0x4nn1 on leaving OP.
class DigitalOutputs {
 public:
  DigitalOutputs(coe::ObjectDictionary& od, const mdp::Module& m)
      : out_(require_object(od, m.index(0x7000, static_cast<uint8_t>(*m.card->output)), m)),
        word_(out_, 1),
        mask_(m.card->channels >= 32 ? 0xFFFFFFFFu : (1u << m.card->channels) - 1u),
        channels_(m.card->channels),
        safe_(
            m.card->safe_state
                ? &require_object(od, m.index(0x4000, static_cast<uint8_t>(*m.card->safe_state)), m)
                : nullptr) {}

  uint32_t commanded() const { return static_cast<uint32_t>(word_.get()) & mask_; }
  uint32_t safe_word(uint32_t current) const {
    if (safe_ == nullptr) return 0;
    return digital_safe_state(current, static_cast<uint32_t>(safe_->get_u(1)),
                              static_cast<uint32_t>(safe_->get_u(2)),
                              static_cast<uint32_t>(safe_->get_u(3)), channels_) &
           mask_;
  }
  unsigned channels() const { return channels_; }
  // 0x4nnX:03 Value (the substitute value of every channel), 0 without the object.
  uint32_t safe_value() const {
    return safe_ == nullptr ? 0 : static_cast<uint32_t>(safe_->get_u(3)) & mask_;
  }
  // Leaving OP: per channel the 0x4nn8 reaction, the guide's rule for 0x8000.
  uint32_t substitute_word(const CardDriver& d, uint32_t current) const {
    const uint32_t guide = safe_word(current);
    const uint32_t value = safe_value();
    uint32_t out = 0;
    for (unsigned n = 0; n < channels_; ++n) {
      const uint32_t bit =
          output_substitute(d.output_reaction(n), (guide >> n) & 1u, (current >> n) & 1u,
                            (value >> n) & 1u, ChannelCodes{});
      out |= (bit & 1u) << n;
    }
    return out;
  }

 private:
  // commanded()'s fields first: it runs every cycle (issue 16).
  coe::Object& out_;
  coe::EntrySlot word_;  // 0x7nnX:01
  uint32_t mask_;
  unsigned channels_;
  coe::Object* safe_;
};

uint32_t driven_word(std::span<const OutputChannel> outs) {
  uint32_t w = 0;
  for (size_t i = 0; i < outs.size(); ++i) w |= (level(outs[i].driven) ? 1u : 0u) << i;
  return w;
}
uint32_t wire_word(std::span<const OutputChannel> outs) {
  uint32_t w = 0;
  for (size_t i = 0; i < outs.size(); ++i) w |= (level(outs[i].wire) ? 1u : 0u) << i;
  return w;
}

class DigitalOutputDriver final : public CardDriver {
 public:
  DigitalOutputDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, 0, m.card->channels),
        dout_(od, m),
        feedback_(m.card->input ? &require_object(
                                      od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)
                                : nullptr),
        sourcing_(m.card->signal == mdp::Signal::DigitalOutSource) {
    if (feedback_ != nullptr) feedback_word_ = coe::EntrySlot(*feedback_, 1);
  }

  void read_outputs() override {
    const uint32_t word = dout_.commanded();
    if (outputs_current(word)) return;  // the channels already drive this word
    for (size_t i = 0; i < outputs_.size(); ++i) outputs_[i].commanded = (word >> i) & 1u;
    drive_word(word);
    outputs_taken(word);
  }
  void apply_safe_state() override {
    drive_word(dout_.substitute_word(*this, driven_word(outputs_)));
  }

  void write_inputs(double, double) override {
    // Force-guided relays report their feedback contacts: the contact state follows the
    // wire (a welded contact shows up as a mismatch against the command).
    if (feedback_ != nullptr) feedback_word_.set(wire_word(outputs_));
  }
  void clear_inputs() override { feedback_word_.set(0); }
  const char* output_unit() const override { return "bit"; }
  // The outputs follow 0x7nnX, the feedback contacts the wire.
  bool time_invariant() const override { return true; }
  bool detects_wiring_faults() const override { return sourcing_; }

 private:
  void drive_word(uint32_t word) {
    for (size_t i = 0; i < outputs_.size(); ++i) {
      const uint32_t bit = (word >> i) & 1u;
      drive(i, bit, bit);
    }
  }

  DigitalOutputs dout_;
  coe::Object* feedback_;
  coe::EntrySlot feedback_word_;  // 0x6nnX:01 when the card has feedback contacts
  bool sourcing_;
};

// E84 (guide Table 3 0x4000): 8 inputs and 8 outputs; DIOx8 subindex 1 carries the inputs,
// subindex 2 the read-back of the outputs as sensed on the terminals.
class DioDriver final : public CardDriver {
 public:
  DioDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, m.card->channels, m.card->channels),
        dout_(od, m),
        in_(require_object(od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)) {}

  void read_outputs() override {
    const uint32_t word = dout_.commanded();
    if (outputs_current(word)) return;  // the channels already drive this word
    for (size_t i = 0; i < outputs_.size(); ++i) outputs_[i].commanded = (word >> i) & 1u;
    drive_word(word);
    outputs_taken(word);
  }
  void apply_safe_state() override {
    drive_word(dout_.substitute_word(*this, driven_word(outputs_)));
  }

  void write_inputs(double t, double) override {
    uint32_t word = 0;
    for (size_t i = 0; i < inputs_.size(); ++i) {
      InputChannel& in = inputs_[i];
      in.value = sample(i, t);
      in.code = level(in.value) ? 1u : 0u;
      word |= in.code << i;
    }
    in_.set_u(1, word);
    in_.set_u(2, wire_word(outputs_));
  }
  void clear_inputs() override {
    in_.set_u(1, 0);
    in_.set_u(2, 0);
    for (auto& in : inputs_) in.code = 0;
  }

 protected:
  void put_input_code(size_t i, uint32_t code) override {
    const auto word = static_cast<uint32_t>(in_.get_u(1));
    in_.set_u(1, (code & 1u) ? word | (1u << i) : word & ~(1u << i));
  }

 public:
  const char* input_unit() const override { return "bit"; }
  const char* output_unit() const override { return "bit"; }
  bool time_invariant() const override { return sources_affine(); }

 private:
  void drive_word(uint32_t word) {
    for (size_t i = 0; i < outputs_.size(); ++i) {
      const uint32_t bit = (word >> i) & 1u;
      drive(i, bit, bit);
    }
  }

  DigitalOutputs dout_;
  coe::Object& in_;
};

}  // namespace

std::unique_ptr<CardDriver> make_digital_input_driver(const mdp::Module& m,
                                                      coe::ObjectDictionary& od) {
  return std::make_unique<DigitalInputDriver>(m, od);
}
std::unique_ptr<CardDriver> make_digital_output_driver(const mdp::Module& m,
                                                       coe::ObjectDictionary& od) {
  return std::make_unique<DigitalOutputDriver>(m, od);
}
std::unique_ptr<CardDriver> make_dio_driver(const mdp::Module& m, coe::ObjectDictionary& od) {
  return std::make_unique<DioDriver>(m, od);
}

}  // namespace rackcat::modules
