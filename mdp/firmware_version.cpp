#include "mdp/firmware_version.hpp"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "mdp/od_helpers.hpp"

namespace rackcat::mdp {

using namespace detail;

namespace {

std::vector<uint8_t> text_bytes(const std::string& text, size_t size) {
  std::vector<uint8_t> v(size, 0);
  std::copy_n(text.begin(), std::min(text.size(), size), v.begin());
  return v;
}

}  // namespace

void apply_firmware_version(coe::ObjectDictionary& od, const ControlModule& cm) {
  // 0x100A: VISIBLE_STRING of the version's length (mdp/objects_communication.cpp).
  const size_t chars = std::max<size_t>(cm.software_version.size(), 1);
  if (const Object* o = od.find(0x100A); o != nullptr) {
    const coe::Entry* e = o->entry(0);
    if (e != nullptr && e->byte_length() == chars) {
      od.find(0x100A)->set_default(0, text_bytes(cm.software_version, chars));
    } else {
      const std::string name = o->name();
      const uint16_t access = e != nullptr ? e->access : acc("ro");
      Object v = var(0x100A, name,
                     str(0, name, static_cast<uint16_t>(chars), access, cm.software_version));
      od.remove(0x100A);
      od.add(std::move(v));
    }
  }
  std::vector<uint8_t> revision(4);
  for (size_t i = 0; i < 4; ++i) revision[i] = static_cast<uint8_t>(cm.revision >> (8 * i));
  if (Object* id = od.find(0x1018)) id->set_default(0x03, revision);
  // 0x2000:02 STRING(4), NUL-padded (guide Appendix A).
  if (Object* info = od.find(0x2000); info != nullptr && info->entry(0x02) != nullptr) {
    info->set_default(0x02, text_bytes(cm.firmware_version, info->entry(0x02)->byte_length()));
  }
}

}  // namespace rackcat::mdp
