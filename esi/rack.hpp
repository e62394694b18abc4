// The esi entry points for the rack: the SII image the ESC serves and the ESI file, both from
// the live mdp::Device (its object dictionary and the fixed SM plan of
// mdp/sync_manager_layout.hpp). apps/rack_slave feeds build_sii() to ecat::Application::eeprom().
#pragma once

#include <string>
#include <vector>

#include "esi/device_description.hpp"
#include "esi/esi_writer.hpp"
#include "esi/sii_image.hpp"
#include "mdp/device.hpp"

namespace rackcat::esi {

// What the SII and ESI say about this device (identity = 0x1018, PDOs = 0x16xx/0x1Axx with the
// assignment 0x1C12/0x1C13, SM sizes from that assignment).
DeviceDescription describe_device(const mdp::Device& device);

// The EEPROM image; its configured station alias (word 4) is 0.
SiiImage build_sii(const mdp::Device& device);

// A rack file with one card of each distinct module ident of the catalogue (24-slot RIMs).
std::string catalogue_rack_yaml();

// One ETG.5001 module per distinct module ident of the card catalogue, described from a
// device built with one card of each ident (its objects and PDOs moved to module 1's indices).
std::vector<ModuleDescription> describe_module_types();

// The whole ESI document for the device, with the Slots/Modules of the catalogue.
std::string write_esi(const mdp::Device& device);

}  // namespace rackcat::esi
