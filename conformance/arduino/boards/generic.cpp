// Board file: any other board on the host core (boards/generic.h): 64 pins,
// UARTs with 64-byte buffers, 1 us a call.
#include "moco_core.h"

// A build may set its own figures: -DMOCO_CLOCK_READ_NS=N -DMOCO_CALL_NS=N.
#ifndef MOCO_CLOCK_READ_NS
#define MOCO_CLOCK_READ_NS 1000
#endif
#ifndef MOCO_CALL_NS
#define MOCO_CALL_NS 1000
#endif

namespace {
constexpr moco::arduino::BoardSpec kGeneric = {
    .name = "generic",
    .pins = 64,
    .uart_rx_buffer_bytes = 64,
    .uart_tx_buffer_bytes = 64,
    .serial_is_usb = false,
    .usb_buffer_bytes = 0,
    .clock_read_ns = MOCO_CLOCK_READ_NS,
    .call_ns = MOCO_CALL_NS,
    .port_write_ns = 125,
    .port_map = nullptr,
    .port_map_size = 0,
    .eeprom_bytes = 1024,
};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kGeneric; }
