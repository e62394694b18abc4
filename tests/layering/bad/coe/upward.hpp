// Deliberate violation for the check's own test: coe/ must not include mdp/.
#pragma once
#include "mdp/device.hpp"
