// Board file: an Arduino GIGA R1 WiFi (STM32H747, M7 core) on the host core.
// The sketch sees the Arduino API; the M4 co-processor, RPC and the STM32 HAL
// are a user's glue (docs/firmware-ci.md, a dual-core board).
#define MOCO_BOARD_GIGA 1
#define ARDUINO_GIGA 1
#define ARDUINO_ARCH_MBED 1
#define ARDUINO_ARCH_MBED_GIGA 1
#ifndef F_CPU
#define F_CPU 480000000L
#endif
#define LEDR 86
#define LEDG 87
#define LEDB 88
