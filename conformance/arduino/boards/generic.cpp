// Board file: any other board on the host core (boards/generic.h): 64 pins,
// UARTs with 64-byte buffers, 1 us a call.
#include "moco_core.h"

namespace {
constexpr moco::arduino::BoardSpec kGeneric = {"generic", 64,   64,  64,      false, 0,
                                               1000,      1000, 125, nullptr, 0,     1024};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kGeneric; }
