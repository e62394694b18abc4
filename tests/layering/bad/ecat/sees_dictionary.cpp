// Deliberate violation (tests/layering/CMakeLists.txt): ecat/ is below every device layer, it never
// sees a dictionary. Compiled with the include path of its layer's library it must fail on the
// second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "ecat/segment.hpp"
// The forbidden one:
#include "coe/object_dictionary.hpp"
