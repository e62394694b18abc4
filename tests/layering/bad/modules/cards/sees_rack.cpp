// Deliberate violation (tests/layering/CMakeLists.txt): slot cards are below the rack.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "modules/cards/card_driver.hpp"
// The forbidden one:
#include "modules/rack/rack.hpp"
