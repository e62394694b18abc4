// Deliberate violation (tests/layering/CMakeLists.txt): the generic CANopen stack depends on coe/
// only. Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "modules/canopen/nmt.hpp"
// The forbidden one:
#include "mdp/device.hpp"
