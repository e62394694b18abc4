// Deliberate violation (tests/layering/CMakeLists.txt): mdp/ knows nothing of the ESC.
// Compiled with the include path of its layer's library it must fail on the second #include
// ("No such file or directory"); check_layers.py must flag that line too.
#include "mdp/sync_manager_layout.hpp"
// The forbidden one:
#include "ecat/esc/esc.hpp"
