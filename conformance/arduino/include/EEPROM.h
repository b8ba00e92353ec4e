// Arduino's EEPROM library on the host core: the board's bytes, erased at start
// (a run starts from a fresh part). The ESP32 form's begin()/commit() accepted.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_EEPROM_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_EEPROM_H_

#include <stddef.h>
#include <stdint.h>

#include "moco_core.h"

class EEPROMClass {
 public:
  class Ref {
   public:
    Ref(size_t address) : address_(address) {}
    operator uint8_t() const { return moco::arduino::EepromRead(address_); }
    Ref& operator=(uint8_t value) {
      moco::arduino::EepromWrite(address_, value);
      return *this;
    }

   private:
    size_t address_;
  };
  bool begin(size_t /*size*/) { return true; }
  bool commit() { return true; }
  void end() {}
  uint8_t read(int address) { return moco::arduino::EepromRead(static_cast<size_t>(address)); }
  void write(int address, uint8_t value) {
    moco::arduino::EepromWrite(static_cast<size_t>(address), value);
  }
  void update(int address, uint8_t value) {
    if (read(address) != value) write(address, value);
  }
  Ref operator[](int address) { return Ref(static_cast<size_t>(address)); }
  size_t length() { return moco::arduino::TheBoard().eeprom_bytes; }
  template <typename T>
  T& get(int address, T& value) {
    uint8_t* p = reinterpret_cast<uint8_t*>(&value);
    for (size_t i = 0; i < sizeof(T); ++i) p[i] = read(address + static_cast<int>(i));
    return value;
  }
  template <typename T>
  const T& put(int address, const T& value) {
    const uint8_t* p = reinterpret_cast<const uint8_t*>(&value);
    for (size_t i = 0; i < sizeof(T); ++i) update(address + static_cast<int>(i), p[i]);
    return value;
  }
};
extern EEPROMClass EEPROM;

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_EEPROM_H_
