// Deliberate violation (tests/layering/CMakeLists.txt): modules/ are below apps/.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "modules/rack/events.hpp"
// The forbidden one:
#include "apps/rack_slave/rack_slave.hpp"
