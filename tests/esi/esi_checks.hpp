// Checks shared by the ESI tests: schema validation with xmllint and the comparison of an ESI
// document with the live object dictionary it was written from.
#pragma once

#include <pugixml.hpp>
#include <set>
#include <string>

#include "coe/object_dictionary.hpp"
#include "esi/device_description.hpp"

namespace rackcat::esi::testing {

// Empty when the schema set is absent (the caller skips), otherwise the xmllint output with
// its exit status; "ok" when the file validates.
std::string schema_dir();
std::string validate_with_xmllint(const std::string& xml, const std::string& name);

// Adds a GoogleTest failure for every object, entry, PDO or SM where `device` (the ESI
// <Device> element) and `od`/`description` disagree, or where the ESI has something the
// dictionary does not.
// `in_modules`: objects defined in the ESI's <Module>s, not at device level (ETG.5001).
void expect_dictionary_matches(const pugi::xml_node& device, const coe::ObjectDictionary& od,
                               const std::set<uint16_t>& in_modules = {});
void expect_pdos_and_sms_match(const pugi::xml_node& device, const DeviceDescription& d);

}  // namespace rackcat::esi::testing
