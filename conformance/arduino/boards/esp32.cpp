// Board file: an ESP32 on the host core (boards/esp32.h): 40 GPIOs, UARTs with
// the ESP32 core's 256-byte receive buffer and the 128-byte hardware FIFO for
// transmit; calls cost what they take at 240 MHz (a GPIO write about 0.1 us).
#include "moco_core.h"

namespace {
constexpr moco::arduino::BoardSpec kEsp32 = {"esp32", 40,  256, 128,     false, 0,
                                             100,     100, 50,  nullptr, 0,     4096};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kEsp32; }
