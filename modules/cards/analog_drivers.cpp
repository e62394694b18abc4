// Analog ±10 V slot cards (guide Table 3 0xF011/0xF015 outputs, 0xF081/0xF085 inputs, Table 5
// x8 oversampled idents): 0x6nn2/3/7/8, 0x7nn2/3, safe states 0x4nn2/0x4nn3 (Tables 9-10).
// Codes follow modules/cards/analog_scale.hpp with the card's 0x3nn1:08/09 voltage range.
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "coe/entry_slot.hpp"
#include "modules/cards/analog_scale.hpp"
#include "modules/cards/drivers.hpp"
#include "modules/cards/safe_state.hpp"
#include "modules/cards/substitute.hpp"

namespace rackcat::modules {
namespace {

AnalogScale module_scale(coe::ObjectDictionary& od, const mdp::Module& m) {
  AnalogScale s{m.card->min_voltage, m.card->max_voltage};
  if (const coe::Object* info = od.find(m.index(0x3000, 1))) {
    if (info->entry(8) && info->entry(9)) {
      // Appendix A has 08 = max, 09 = min, Table 6 the other way round: take them by value.
      const double a = read_real32(*info, 8), b = read_real32(*info, 9);
      s.min_v = std::min(a, b);
      s.max_v = std::max(a, b);
    }
  }
  if (!(s.max_v > s.min_v)) {
    throw std::runtime_error(
        fmt::format("module {}: 0x3nn1 voltage range {}..{} is empty", m.number, s.min_v, s.max_v));
  }
  return s;
}

class AnalogInputDriver final : public CardDriver {
 public:
  AnalogInputDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, m.card->channels, 0),
        obj_(require_object(od, m.index(0x6000, static_cast<uint8_t>(*m.card->input)), m)),
        scale_(module_scale(od, m)),
        samples_(m.card->samples) {
    for (size_t i = 0; i < inputs_.size(); ++i)
      slots_.emplace_back(obj_, static_cast<uint8_t>(i + 1));
    if (samples_ > 1) {
      raw_.resize(inputs_.size());
      for (size_t i = 0; i < inputs_.size(); ++i) {
        raw_[i] = obj_.bytes(static_cast<uint8_t>(i + 1));
        if (raw_[i].size() < 2u * samples_)
          throw std::runtime_error(fmt::format("module {}: sample array too small", m.number));
      }
    }
  }

  void write_inputs(double t, double dt) override {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      InputChannel& in = inputs_[i];
      if (samples_ == 1) {
        in.value = sample(i, t);
        in.code = scale_.to_code(in.value);
        slots_[i].set(in.code);
        continue;
      }
      // Sample k at t - dt + (k+1) dt/8; element 0 is the oldest.
      const bool varies = source(i).varies_within_cycle();
      for (unsigned k = 0; k < samples_; ++k) {
        if (varies || k == 0) {
          in.value = sample(i, varies ? t - dt + (k + 1) * dt / samples_ : t);
          in.code = scale_.to_code(in.value);
        }
        raw_[i][2 * k] = static_cast<uint8_t>(in.code);
        raw_[i][2 * k + 1] = static_cast<uint8_t>(in.code >> 8);
      }
    }
  }

  void clear_inputs() override {
    for (size_t i = 0; i < inputs_.size(); ++i) {
      inputs_[i].code = 0;
      if (samples_ == 1) {
        obj_.set_u(static_cast<uint8_t>(i + 1), 0);
      } else {
        std::fill(raw_[i].begin(), raw_[i].end(), uint8_t{0});
      }
    }
  }
  const char* input_unit() const override { return "V"; }

 protected:
  void put_input_code(size_t i, uint32_t code) override {
    if (samples_ == 1) {
      slots_[i].set(code);
      return;
    }
    for (unsigned k = 0; k < samples_; ++k) {
      raw_[i][2 * k] = static_cast<uint8_t>(code);
      raw_[i][2 * k + 1] = static_cast<uint8_t>(code >> 8);
    }
  }

 private:
  coe::Object& obj_;
  AnalogScale scale_;
  unsigned samples_;
  std::vector<std::span<uint8_t>> raw_;
  std::vector<coe::EntrySlot> slots_;
};

class AnalogOutputDriver final : public CardDriver {
 public:
  AnalogOutputDriver(const mdp::Module& m, coe::ObjectDictionary& od)
      : CardDriver(m, od, 0, m.card->channels),
        out_(require_object(od, m.index(0x7000, static_cast<uint8_t>(*m.card->output)), m)),
        safe_(
            m.card->safe_state
                ? &require_object(od, m.index(0x4000, static_cast<uint8_t>(*m.card->safe_state)), m)
                : nullptr),
        scale_(module_scale(od, m)) {}

  void read_outputs() override {
    for (size_t i = 0; i < outputs_.size(); ++i) {
      const auto code = static_cast<uint16_t>(out_.get_u(static_cast<uint8_t>(i + 1)));
      outputs_[i].commanded = scale_.to_volts(code);
      drive(i, scale_.to_volts(code), code);
    }
  }

  // Leaving OP: per channel the 0x4nn8 reaction (substitute.hpp); 0x8000 is the guide's rule.
  // Extremes: all 16 bits set, and the codes of the card's voltage range (0x3nn1:08/09).
  void apply_safe_state() override {
    const uint32_t enable = safe_ ? static_cast<uint32_t>(safe_->get_u(1)) : 0;
    const uint32_t action = safe_ ? static_cast<uint32_t>(safe_->get_u(2)) : 0;
    const ChannelCodes extremes{0xFFFF, scale_.to_code(scale_.min_v), scale_.to_code(scale_.max_v)};
    for (size_t i = 0; i < outputs_.size(); ++i) {
      const auto value =
          safe_ ? static_cast<uint16_t>(safe_->get_u(static_cast<uint8_t>(3 + i))) : uint16_t{0};
      const auto current = static_cast<uint16_t>(outputs_[i].code);
      const uint16_t guide =
          analog_safe_state(current, enable, action, value, static_cast<unsigned>(i));
      const auto code = static_cast<uint16_t>(
          output_substitute(output_reaction(i), guide, current, value, extremes));
      drive(i, scale_.to_volts(code), code);
    }
  }

  void write_inputs(double, double) override {}
  void clear_inputs() override {}
  const char* output_unit() const override { return "V"; }

 private:
  coe::Object& out_;
  coe::Object* safe_;
  AnalogScale scale_;
};

}  // namespace

std::unique_ptr<CardDriver> make_analog_input_driver(const mdp::Module& m,
                                                     coe::ObjectDictionary& od) {
  return std::make_unique<AnalogInputDriver>(m, od);
}
std::unique_ptr<CardDriver> make_analog_output_driver(const mdp::Module& m,
                                                      coe::ObjectDictionary& od) {
  return std::make_unique<AnalogOutputDriver>(m, od);
}

}  // namespace rackcat::modules
