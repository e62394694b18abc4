// Allowed (tests/layering/CMakeLists.txt): everything the firmware may include. Compiled with
// rackcat_ecat_slave's include path it must build; check_layers.py must flag nothing here.
#include "base/esm_state.hpp"
#include "ecat/al_status_code.hpp"
#include "ecat/application.hpp"
#include "ecat/pdi_port.hpp"
#include "ecat/registers.hpp"
#include "ecat/slave/mailbox_server.hpp"
