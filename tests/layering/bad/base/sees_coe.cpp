// Deliberate violation (tests/layering/CMakeLists.txt): base/ is below every layer.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "base/little_endian.hpp"
// The forbidden one:
#include "coe/abort_code.hpp"
