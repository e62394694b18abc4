// Deliberate violation for the check's own test: the chip knows nothing of the firmware.
#pragma once
#include "ecat/slave/firmware.hpp"
