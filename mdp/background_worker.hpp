// The device's background worker is the process-wide one of base/ (base/background_worker.hpp),
// shared with the FoE files of devices emulated from their ESI; mdp code names it
// mdp::BackgroundWorker.
#pragma once

#include "base/background_worker.hpp"

namespace rackcat::mdp {

using base::BackgroundWorker;

}  // namespace rackcat::mdp
