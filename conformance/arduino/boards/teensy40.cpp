// Board file: a Teensy 4.0 on the host core (boards/teensy40.h): 40 pins,
// Serial over USB (not paced, the host waits when its buffer is full),
// Serial1/Serial2 UARTs with Teensyduino's 64-byte buffers; calls at 600 MHz.
#include "moco_core.h"

namespace {
constexpr moco::arduino::BoardSpec kTeensy40 = {"teensy40", 40, 64, 40,      true, 4096,
                                                50,         50, 20, nullptr, 0,    1080};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kTeensy40; }
