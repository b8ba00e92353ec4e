// The Arduino API on the host core: types, the clock, pins, interrupts and the
// serial ports, each call a point where simulated time moves (moco_core.h).
// The board header given before it (conformance/arduino/boards/NAME.h) says
// which board API set a sketch also sees: an ESP32's hw_timer, portMUX and
// IRAM_ATTR; a Teensy's IntervalTimer and elapsedMillis; an AVR's ports; an
// mbed board's ArduinoCore-API names (pin_size_t, PinStatus, RingBufferN).
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_ARDUINO_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_ARDUINO_H_

#include <ctype.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <algorithm>

#include "HardwareSerial.h"
#include "Print.h"
#include "Stream.h"
#include "WString.h"
#include "avr/pgmspace.h"
#include "moco_core.h"

#ifndef ARDUINO
#define ARDUINO 10819
#endif
#define MOCO_NATIVE 1

#define HIGH 0x1
#define LOW 0x0
#define INPUT 0x0
#define OUTPUT 0x1
#define INPUT_PULLUP 0x2
#define INPUT_PULLDOWN 0x3
#define LSBFIRST 0
#define MSBFIRST 1
#define CHANGE 1
#define FALLING 2
#define RISING 3
#define LED_BUILTIN 13
#define NOT_AN_INTERRUPT -1

#define PI 3.1415926535897932384626433832795
#define HALF_PI 1.5707963267948966192313216916398
#define TWO_PI 6.283185307179586476925286766559
#define DEG_TO_RAD 0.017453292519943295769236907684886
#define RAD_TO_DEG 57.295779513082320876798154814105

typedef bool boolean;
typedef uint8_t byte;
typedef uint16_t word;

template <typename A, typename B>
constexpr auto min(const A& a, const B& b) -> decltype(a < b ? a : b) {
  return b < a ? b : a;
}
template <typename A, typename B>
constexpr auto max(const A& a, const B& b) -> decltype(a < b ? a : b) {
  return a < b ? b : a;
}
#define constrain(amt, low, high) ((amt) < (low) ? (low) : ((amt) > (high) ? (high) : (amt)))
#define radians(deg) ((deg)*DEG_TO_RAD)
#define degrees(rad) ((rad)*RAD_TO_DEG)
#define sq(x) ((x) * (x))
#define lowByte(w) ((uint8_t)((w)&0xff))
#define highByte(w) ((uint8_t)((w) >> 8))
#define bit(b) (1UL << (b))
#define bitRead(value, b) (((value) >> (b)) & 0x01)
#define bitSet(value, b) ((value) |= (1UL << (b)))
#define bitClear(value, b) ((value) &= ~(1UL << (b)))
#define bitWrite(value, b, v) ((v) ? bitSet(value, b) : bitClear(value, b))
#define digitalPinToInterrupt(p) (p)
#define clockCyclesPerMicrosecond() (F_CPU / 1000000L)

// avr-libc's and the ESP32 core's number-to-text conversions (base 2..36).
char* itoa(int value, char* buffer, int base);
char* ltoa(long value, char* buffer, int base);
char* utoa(unsigned value, char* buffer, int base);
char* ultoa(unsigned long value, char* buffer, int base);
char* dtostrf(double value, signed char width, unsigned char precision, char* buffer);

long map(long x, long in_min, long in_max, long out_min, long out_max);
word makeWord(uint8_t high, uint8_t low);

// The clock, in simulated time; each read costs the board's clock read.
unsigned long millis();
unsigned long micros();
void delay(unsigned long ms);
void delayMicroseconds(unsigned int us);
void yield();

void pinMode(uint8_t pin, uint8_t mode);
void digitalWrite(uint8_t pin, uint8_t level);
int digitalRead(uint8_t pin);
int analogRead(uint8_t pin);
void analogWrite(uint8_t pin, int value);
void analogReference(uint8_t mode);
void attachInterrupt(uint8_t interrupt, void (*isr)(), int mode);
void detachInterrupt(uint8_t interrupt);
void tone(uint8_t pin, unsigned int frequency, unsigned long duration_ms = 0);
void noTone(uint8_t pin);
unsigned long pulseIn(uint8_t pin, uint8_t state, unsigned long timeout_us = 1000000L);
void shiftOut(uint8_t data_pin, uint8_t clock_pin, uint8_t bit_order, uint8_t value);

inline void interrupts() { moco::arduino::InterruptsOn(); }
inline void noInterrupts() { moco::arduino::InterruptsOff(); }

// Deterministic: the same seed, the same numbers on every run.
long random(long max);
long random(long min, long max);
void randomSeed(unsigned long seed);

void setup();
void loop();

// ArduinoCore-API, which the mbed cores build on: its names for a pin number
// and a level (an int here, as HIGH and LOW are), and RingBufferN.
#ifdef ARDUINO_ARCH_MBED
typedef uint8_t pin_size_t;
typedef int PinStatus;
#include "RingBuffer.h"
#endif

#ifdef MOCO_API_ESP32
#include "esp32-hal.h"
#endif
#ifdef MOCO_API_TEENSY
// Teensyduino's placement attributes (tightly coupled memory, flash, DMA RAM).
#define FASTRUN
#define FLASHMEM
#define DMAMEM
// Teensyduino's fast pin access: a port write's cost, not a call's.
inline void digitalWriteFast(uint8_t pin, uint8_t level) {
  moco::arduino::Spend(moco::arduino::TheBoard().port_write_ns);
  moco::arduino::PinWrite(pin, level != LOW);
}
inline int digitalReadFast(uint8_t pin) { return moco::arduino::PinRead(pin) ? HIGH : LOW; }
#include "IntervalTimer.h"
#include "elapsedMillis.h"
#endif

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_ARDUINO_H_
