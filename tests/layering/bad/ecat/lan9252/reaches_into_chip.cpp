// Deliberate violation (tests/layering/CMakeLists.txt): the LAN9252 access sees the chip only
// through ecat/pdi_port.hpp. Compiled with the include path of its layer's library it must fail on
// the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "ecat/lan9252/lan9252_bus.hpp"
// The forbidden one:
#include "ecat/esc/esc.hpp"
