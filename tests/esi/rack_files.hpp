// Rack files the esi tests and benchmarks share.
#pragma once

#include <cstddef>
#include <string>

#include "mdp/card_catalogue.hpp"

namespace rackcat::esi::testing {

// 120 modules, the most a rack file can hold: five 24-slot RIMs filled with the catalogue's
// cards in turn.
inline std::string rack_120_yaml() {
  std::string yaml = "rims:\n";
  auto cards = mdp::card_catalogue();
  for (int rim = 1; rim <= 5; ++rim) {
    yaml += "  - rim: " + std::to_string(rim) + "\n    type: 24-slot\n    slots:\n";
    for (int slot = 1; slot <= 24; ++slot) {
      const auto& card = cards[static_cast<size_t>((rim - 1) * 24 + slot - 1) % cards.size()];
      yaml += "      - {slot: " + std::to_string(slot) + ", card: \"" + std::string(card.name) +
              "\"}\n";
    }
  }
  return yaml;
}

}  // namespace rackcat::esi::testing
