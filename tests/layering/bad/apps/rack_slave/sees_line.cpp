// Deliberate violation (tests/layering/CMakeLists.txt): the rack slave is below the line.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "apps/rack_slave/rack_loading.hpp"
// The forbidden one:
#include "apps/line/line_file.hpp"
