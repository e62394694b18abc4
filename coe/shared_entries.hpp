// Object and entry descriptions shared between objects described identically (per-slave
// memory proportional to what the slave uses). 256 identical slaves build 256 dictionaries
// whose objects describe themselves identically (names, object codes, types, and the entries'
// names, types, bit layout, access, limits, defaults: ETG.1000.6 §5.6.3.5, §5.6.3.6); only the
// value images differ per slave. When an object enters a dictionary its description is
// interned here: an equal one already in use elsewhere is shared (read-only, reference
// counted) and the new copy is freed. Entry lists are interned on their own as well, so objects
// with different names but identical entries (one per module slot) share the list.
//
// Start-up only (dictionary construction); thread safe. The tables hold weak references, so
// a description no object uses any more is freed with its last user.
#pragma once

#include <memory>
#include <vector>

#include "coe/object_dictionary.hpp"

namespace rackcat::coe {

// Returns an existing list equal to `*entries` if one is in use, else registers and returns
// `entries` itself.
std::shared_ptr<const std::vector<Entry>> intern_entries(
    std::shared_ptr<const std::vector<Entry>> entries);

// The same for a whole description (its entry list interned first).
std::shared_ptr<const ObjectDescription> intern_description(
    std::shared_ptr<const ObjectDescription> desc);

}  // namespace rackcat::coe
