// Deliberate violation (tests/layering/CMakeLists.txt): coe/ must not see the modular device above
// it. Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "coe/abort_code.hpp"
// The forbidden one:
#include "mdp/device.hpp"
