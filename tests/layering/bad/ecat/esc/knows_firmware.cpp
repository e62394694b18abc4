// Deliberate violation (tests/layering/CMakeLists.txt): the chip knows nothing of the firmware.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "ecat/esc/esc.hpp"
// The forbidden one:
#include "ecat/slave/firmware.hpp"
