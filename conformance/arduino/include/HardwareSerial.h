// A serial port of the host core (Serial, Serial1, Serial2): the board's
// buffer sizes, bytes on the line at the baud begin() sets (include/moco_core.h).
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_HARDWARESERIAL_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_HARDWARESERIAL_H_

#include <stdint.h>

#include "Stream.h"

#define SERIAL_8N1 0x06
#define SERIAL_8N2 0x0E
#define SERIAL_8E1 0x26
#define SERIAL_8O1 0x36

class HardwareSerial : public Stream {
 public:
  explicit HardwareSerial(int port) : port_(port) {}
  void begin(unsigned long baud) { begin(baud, SERIAL_8N1); }
  // The ESP32 core's form (config, pins, invert) is taken; only the baud matters.
  void begin(unsigned long baud, uint32_t config, int8_t rx_pin = -1, int8_t tx_pin = -1,
             bool invert = false);
  void end();
  int available() override;
  int peek() override;
  int read() override;
  int availableForWrite() override;
  void flush() override;
  size_t write(uint8_t value) override;
  size_t write(const uint8_t* buffer, size_t size) override;
  using Print::write;
  operator bool() const { return true; }
  // Teensy's and other USB ports' extras.
  bool dtr() { return true; }
  uint32_t baud() const { return baud_; }

 private:
  int port_;
  uint32_t baud_ = 0;
};

extern HardwareSerial Serial;
extern HardwareSerial Serial1;
extern HardwareSerial Serial2;

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_HARDWARESERIAL_H_
