// The ESP32 core's BluetoothSerial (classic SPP) on the host core: a second
// serial port the runner can speak the protocol on (--target native:FW@bluetooth);
// the radio is not modelled: bytes come and go without line pacing or loss.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_BLUETOOTHSERIAL_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_BLUETOOTHSERIAL_H_

#include "Stream.h"
#include "WString.h"
#include "moco_core.h"

class BluetoothSerial : public Stream {
 public:
  bool begin(const String& local_name = String("ESP32"), bool is_master = false);
  void end();
  bool hasClient() { return begun_; }
  bool connected(int /*timeout_ms*/ = 0) { return begun_; }
  int available() override;
  int peek() override;
  int read() override;
  void flush() override;
  size_t write(uint8_t value) override;
  size_t write(const uint8_t* buffer, size_t size) override;
  using Print::write;
  operator bool() const { return begun_; }

 private:
  bool begun_ = false;
};

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_BLUETOOTHSERIAL_H_
