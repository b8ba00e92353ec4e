// Board file: an ESP32 DevKit on the host core. The sketch sees the ESP32
// core's API set: hw_timer, portMUX critical sections, IRAM_ATTR,
// BluetoothSerial, Serial1/Serial2.
#define MOCO_BOARD_ESP32 1
#define MOCO_API_ESP32 1
#define ESP32 1
#define ARDUINO_ARCH_ESP32 1
#define ARDUINO_ESP32_DEV 1
#ifndef F_CPU
#define F_CPU 240000000L
#endif
