// Allowed (tests/layering/CMakeLists.txt): a device from its ESI sees coe/, esi/ and the device
// seam of ecat/. Compiled with rackcat_device's include path it must build; check_layers.py
// must flag nothing here.
#include "coe/object_dictionary.hpp"
#include "ecat/application.hpp"
#include "ecat/slave/mailbox_protocol.hpp"
#include "esi/sii_image.hpp"
