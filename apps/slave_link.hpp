// The ESC side of every slave for the web page's line view (modules/control/live_snapshot.hpp):
// registers read on the device thread when the page's snapshot is taken.
#pragma once

#include "ecat/host/event_loop.hpp"
#include "ecat/segment.hpp"
#include "modules/control/live_snapshot.hpp"

namespace rackcat::apps {

// Reads station address, AL status and code, the process-data watchdog and the RX error
// counters (ETG.1000.4 §6) of the control API's slave N (= line position N), the identity from
// its SII (ETG.2010 Table 2) and the loop's frame count. Device thread; no allocation.
modules::SlaveLinkFn slave_link(ecat::Segment& segment, ecat::EventLoop& loop);

}  // namespace rackcat::apps
