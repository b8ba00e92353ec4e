// Board file: an Arduino Uno (ATmega328P, 16 MHz) on the host core. The sketch
// sees the AVR API set: PORTB/C/D writes mapped to pins 8-13, A0-A5, 0-7.
#define MOCO_BOARD_UNO 1
#define MOCO_API_AVR_PORTS 1
#define ARDUINO_AVR_UNO 1
#define ARDUINO_ARCH_AVR 1
#ifndef F_CPU
#define F_CPU 16000000L
#endif
#define SERIAL_RX_BUFFER_SIZE 64
#define SERIAL_TX_BUFFER_SIZE 64
