// Deliberate violation for the check's own test: the firmware sees the chip only through
// ecat/pdi_port.hpp, never the chip's own headers.
#pragma once
#include "ecat/esc/esc.hpp"
