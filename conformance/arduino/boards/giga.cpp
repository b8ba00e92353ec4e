// Board file: an Arduino GIGA R1 on the host core (boards/giga.h): 103 pins,
// Serial over USB (not paced, the host waits when its buffer is full), calls
// costing what they take at 480 MHz.
#include "moco_core.h"

// A build may set its own figures: -DMOCO_CLOCK_READ_NS=N -DMOCO_CALL_NS=N.
#ifndef MOCO_CLOCK_READ_NS
#define MOCO_CLOCK_READ_NS 50
#endif
#ifndef MOCO_CALL_NS
#define MOCO_CALL_NS 50
#endif

namespace {
constexpr moco::arduino::BoardSpec kGiga = {
    .name = "giga",
    .pins = 103,
    .uart_rx_buffer_bytes = 64,
    .uart_tx_buffer_bytes = 64,
    .serial_is_usb = true,
    .usb_buffer_bytes = 4096,
    .clock_read_ns = MOCO_CLOCK_READ_NS,
    .call_ns = MOCO_CALL_NS,
    .port_write_ns = 20,
    .port_map = nullptr,
    .port_map_size = 0,
    .eeprom_bytes = 4096,
};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kGiga; }
