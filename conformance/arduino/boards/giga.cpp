// Board file: an Arduino GIGA R1 on the host core (boards/giga.h): 103 pins,
// Serial over USB (not paced, the host waits when its buffer is full), calls
// costing what they take at 480 MHz.
#include "moco_core.h"

namespace {
constexpr moco::arduino::BoardSpec kGiga = {"giga", 103, 64, 64,      true, 4096,
                                            50,     50,  20, nullptr, 0,    4096};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kGiga; }
