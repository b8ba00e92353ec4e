// Board file: an ESP32 on the host core (boards/esp32.h): 40 GPIOs, UARTs with
// the ESP32 core's 256-byte receive buffer and the 128-byte hardware FIFO for
// transmit; calls cost what they take at 240 MHz (a GPIO write about 0.1 us).
#include "moco_core.h"

// A build may set its own figures: -DMOCO_CLOCK_READ_NS=N -DMOCO_CALL_NS=N.
#ifndef MOCO_CLOCK_READ_NS
#define MOCO_CLOCK_READ_NS 100
#endif
#ifndef MOCO_CALL_NS
#define MOCO_CALL_NS 100
#endif

namespace {
constexpr moco::arduino::BoardSpec kEsp32 = {
    .name = "esp32",
    .pins = 40,
    .uart_rx_buffer_bytes = 256,
    .uart_tx_buffer_bytes = 128,
    .serial_is_usb = false,
    .usb_buffer_bytes = 0,
    .clock_read_ns = MOCO_CLOCK_READ_NS,
    .call_ns = MOCO_CALL_NS,
    .port_write_ns = 50,
    .port_map = nullptr,
    .port_map_size = 0,
    .eeprom_bytes = 4096,
};
}  // namespace

const moco::arduino::BoardSpec& moco::arduino::TheBoard() { return kEsp32; }
