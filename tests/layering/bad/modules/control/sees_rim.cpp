// Deliberate violation (tests/layering/CMakeLists.txt): the control API does not see the RIM link.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "modules/rack/events.hpp"
// The forbidden one:
#include "modules/rim/master.hpp"
