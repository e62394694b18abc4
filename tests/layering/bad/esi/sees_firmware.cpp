// Deliberate violation (tests/layering/CMakeLists.txt): esi/ describes a device, it does not run
// one. Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "esi/sii_crc.hpp"
// The forbidden one:
#include "ecat/slave/firmware.hpp"
