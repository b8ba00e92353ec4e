// Board file: a Teensy 4.0 on the host core (boards/teensy40.h): 40 pins,
// Serial over USB (not paced, the host waits when its buffer is full),
// Serial1/Serial2 UARTs with Teensyduino's 64-byte buffers; calls at 600 MHz.
#include "moco_core.h"

// A build may set its own figures: -DMOCO_CLOCK_READ_NS=N -DMOCO_CALL_NS=N.
#ifndef MOCO_CLOCK_READ_NS
#define MOCO_CLOCK_READ_NS 50
#endif
#ifndef MOCO_CALL_NS
#define MOCO_CALL_NS 50
#endif

namespace {
constexpr moco::arduino::BoardSpec kTeensy40 = {
    .name = "teensy40",
    .pins = 40,
    .uart_rx_buffer_bytes = 64,
    .uart_tx_buffer_bytes = 40,
    .serial_is_usb = true,
    .usb_buffer_bytes = 4096,
    .clock_read_ns = MOCO_CLOCK_READ_NS,
    .call_ns = MOCO_CALL_NS,
    .port_write_ns = 20,
    .port_map = nullptr,
    .port_map_size = 0,
    .eeprom_bytes = 1080,
};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kTeensy40; }
