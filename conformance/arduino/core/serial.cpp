// The host core's serial ports as Arduino objects (include/HardwareSerial.h,
// BluetoothSerial.h) over the runtime's ports (moco_core.h).
#include "BluetoothSerial.h"
#include "HardwareSerial.h"
#include "moco_core.h"

namespace ar = moco::arduino;

HardwareSerial Serial(0);
HardwareSerial Serial1(1);
HardwareSerial Serial2(2);

void HardwareSerial::begin(unsigned long baud, uint32_t /*config*/, int8_t /*rx_pin*/,
                           int8_t /*tx_pin*/, bool /*invert*/) {
  baud_ = static_cast<uint32_t>(baud);
  ar::SerialBegin(port_, baud_);
}
void HardwareSerial::end() { ar::SerialEnd(port_); }
int HardwareSerial::available() { return ar::SerialAvailable(port_); }
int HardwareSerial::peek() { return ar::SerialPeek(port_); }
int HardwareSerial::read() { return ar::SerialRead(port_); }
int HardwareSerial::availableForWrite() { return ar::SerialAvailableForWrite(port_); }
void HardwareSerial::flush() { ar::SerialFlush(port_); }
size_t HardwareSerial::write(uint8_t value) {
  ar::SerialWrite(port_, value);
  return 1;
}
size_t HardwareSerial::write(const uint8_t* buffer, size_t size) {
  for (size_t i = 0; i < size; ++i) ar::SerialWrite(port_, buffer[i]);
  return size;
}

bool BluetoothSerial::begin(const String& /*local_name*/, bool /*is_master*/) {
  begun_ = true;
  ar::SerialBegin(ar::kBluetoothPort, 0);
  return true;
}
void BluetoothSerial::end() {
  begun_ = false;
  ar::SerialEnd(ar::kBluetoothPort);
}
int BluetoothSerial::available() { return ar::SerialAvailable(ar::kBluetoothPort); }
int BluetoothSerial::peek() { return ar::SerialPeek(ar::kBluetoothPort); }
int BluetoothSerial::read() { return ar::SerialRead(ar::kBluetoothPort); }
void BluetoothSerial::flush() { ar::SerialFlush(ar::kBluetoothPort); }
size_t BluetoothSerial::write(uint8_t value) {
  ar::SerialWrite(ar::kBluetoothPort, value);
  return 1;
}
size_t BluetoothSerial::write(const uint8_t* buffer, size_t size) {
  for (size_t i = 0; i < size; ++i) ar::SerialWrite(ar::kBluetoothPort, buffer[i]);
  return size;
}
