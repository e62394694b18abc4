// Deliberate violation (tests/layering/CMakeLists.txt): signal models need nothing of the device.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "modules/signals/signal_source.hpp"
// The forbidden one:
#include "mdp/device.hpp"
