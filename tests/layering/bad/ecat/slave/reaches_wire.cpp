// Deliberate violation (tests/layering/CMakeLists.txt): the firmware sees no frames, only the PDI
// port. Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "ecat/pdi_port.hpp"
// The forbidden one:
#include "ecat/frame.hpp"
