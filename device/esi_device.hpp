// One device of a vendor's ESI file (ETG.2000 EtherCATInfo) turned into what rackcat serves:
// the DeviceDescription the SII image is encoded from (identity, General, FMMU, SM, PDO and DC
// categories, ETG.2010) and, for a device with a CoE mailbox, the object dictionary of its
// <Profile><Dictionary> (ETG.2000 §"DictionaryType": DataTypes and Objects with defaults,
// access per state and PDO mappability). Mapping objects 0x1600../0x1A00.., the assignment
// 0x1C12/0x1C13 and the identity 0x1018 a Dictionary leaves out are derived from the RxPdo,
// TxPdo and Type elements, so SII and CoE agree. A device without <Mailbox><CoE> works from
// the SII alone.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "coe/object_dictionary.hpp"
#include "esi/device_description.hpp"

namespace rackcat::device {

// One module of a chosen module list (ETG.5001 modular device): its ModuleIdent ("0x0064E001",
// "#x0064E001" or decimal) or its Module/Type text (or one of the comma-separated names in it,
// "CRS-10" for "CRS-10, COO-11"). `file`/`line` say where the choice was written (the line
// file), for the error an unknown or misplaced module gets.
struct ModuleChoice {
  std::string ref;
  std::string file;
  size_t line = 0;
};

// Which <Device> of the file: by its Type text or Name (exact), or by product code and, when
// given, revision. An empty selector takes the file's only device. `modules`, when set, fills
// the device's <Slots> with these modules in order (slot position 1, 2, ...); without it a
// modular device is served as its device-level content describes it.
struct DeviceSelector {
  std::string name;
  std::optional<uint32_t> product_code;
  std::optional<uint32_t> revision;
  std::optional<std::vector<ModuleChoice>> modules;

  static DeviceSelector named(std::string n) {
    DeviceSelector s;
    s.name = std::move(n);
    return s;
  }
  static DeviceSelector by_code(uint32_t code, std::optional<uint32_t> rev = std::nullopt) {
    DeviceSelector s;
    s.product_code = code;
    s.revision = rev;
    return s;
  }
};

struct EsiDevice {
  esi::DeviceDescription description;
  bool has_coe = false;
  coe::ObjectDictionary dictionary;     // empty without CoE
  std::string file;                     // where it came from (for messages)
  std::vector<uint32_t> module_idents;  // the chosen modules (0xF030/0xF050), slot order
};

// Parses `xml` (the content of `file`). Throws FileError naming the file and line of the first
// unsupported or contradictory element: no matching device, an unknown data type, a PDO entry
// larger than its SM's MaxSize, a SubItem beyond its type, a malformed number.
EsiDevice parse_esi_device(std::string_view xml, const std::string& file,
                           const DeviceSelector& selector);

// Reads `file` (a regular file; not a link) and parses it.
EsiDevice load_esi_device(const std::string& file, const DeviceSelector& selector);

// "#x1A" (ETG.2000 HexDecValue) or decimal; nullopt when malformed.
std::optional<int64_t> parse_hex_dec(std::string_view text);

}  // namespace rackcat::device
