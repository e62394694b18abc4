// Part of the check's own test tree: what the firmware may include (no violation).
#pragma once
#include "ecat/pdi_port.hpp"
