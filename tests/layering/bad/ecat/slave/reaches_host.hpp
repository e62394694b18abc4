// Deliberate violation for the check's own test: the firmware does not see the host I/O.
#pragma once
#include "ecat/host/runner.hpp"
