// Board file: an Arduino Uno on the host core (boards/uno.h). Serial is the
// ATmega328P's USART with the AVR core's 64-byte buffers; the port map is the
// Uno's pin mapping (PD0-7: pins 0-7, PB0-5: pins 8-13, PC0-5: pins 14-19).
#include "moco_core.h"

// A build may set its own figures: -DMOCO_CLOCK_READ_NS=N -DMOCO_CALL_NS=N.
#ifndef MOCO_CLOCK_READ_NS
#define MOCO_CLOCK_READ_NS 1500
#endif
#ifndef MOCO_CALL_NS
#define MOCO_CALL_NS 4000
#endif

namespace {
constexpr moco::arduino::PortPin kPorts[] = {
    {0, 'D', 0},  {1, 'D', 1},  {2, 'D', 2},  {3, 'D', 3},  {4, 'D', 4},
    {5, 'D', 5},  {6, 'D', 6},  {7, 'D', 7},  {8, 'B', 0},  {9, 'B', 1},
    {10, 'B', 2}, {11, 'B', 3}, {12, 'B', 4}, {13, 'B', 5}, {14, 'C', 0},
    {15, 'C', 1}, {16, 'C', 2}, {17, 'C', 3}, {18, 'C', 4}, {19, 'C', 5},
};
// A digitalWrite() takes about 4 us on an Uno's core, millis() about 1.5 us;
// a port write is two cycles.
constexpr moco::arduino::BoardSpec kUno = {
    .name = "uno",
    .pins = 20,
    .uart_rx_buffer_bytes = 64,
    .uart_tx_buffer_bytes = 64,
    .serial_is_usb = false,
    .usb_buffer_bytes = 0,
    .clock_read_ns = MOCO_CLOCK_READ_NS,
    .call_ns = MOCO_CALL_NS,
    .port_write_ns = 125,
    .port_map = kPorts,
    .port_map_size = sizeof(kPorts) / sizeof(kPorts[0]),
    .eeprom_bytes = 1024,
};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kUno; }
