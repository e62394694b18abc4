// Entry descriptions shared between objects with identical descriptions (per-slave
// memory proportional to what the slave uses). 256 identical slaves build 256 dictionaries
// whose objects describe their entries identically (names, types, bit layout, access, limits,
// defaults, ETG.1000.6 §5.6.3.6 entry descriptions); only the value images differ per slave.
// When an object enters a dictionary its entry list is interned here: an equal list already
// in use elsewhere is shared (read-only, reference counted) and the new copy is freed.
//
// Start-up only (dictionary construction); thread safe. The table holds weak references, so
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

}  // namespace rackcat::coe
