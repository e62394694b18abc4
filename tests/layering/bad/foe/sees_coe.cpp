// Deliberate violation (tests/layering/CMakeLists.txt): foe/ is a protocol of its own, beside coe/.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "foe/foe_error.hpp"
// The forbidden one:
#include "coe/abort_code.hpp"
