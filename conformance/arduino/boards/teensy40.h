// Board file: a Teensy 4.0 on the host core. The sketch sees Teensyduino's API
// set: IntervalTimer, elapsedMillis/elapsedMicros; Serial is USB.
#define MOCO_BOARD_TEENSY40 1
#define MOCO_API_TEENSY 1
#define TEENSYDUINO 159
#define ARDUINO_TEENSY40 1
#define __IMXRT1062__ 1
#ifndef F_CPU
#define F_CPU 600000000L
#endif
