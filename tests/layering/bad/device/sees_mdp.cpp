// Deliberate violation (tests/layering/CMakeLists.txt): a device from its ESI does not see the
// modular device. Compiled with the include path of its layer's library it must fail on the second
// #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "ecat/application.hpp"
// The forbidden one:
#include "mdp/device.hpp"
