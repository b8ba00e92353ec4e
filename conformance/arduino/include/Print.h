// Arduino's Print on the host core: formatted output over a write(uint8_t).
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_PRINT_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_PRINT_H_

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "WString.h"

#define DEC 10
#define HEX 16
#define OCT 8
#define BIN 2

class Print;
// Something a sketch can print itself (Printable::printTo).
class Printable {
 public:
  virtual ~Printable() = default;
  virtual size_t printTo(Print& p) const = 0;
};

class Print {
 public:
  virtual ~Print() = default;
  virtual size_t write(uint8_t value) = 0;
  virtual size_t write(const uint8_t* buffer, size_t size);
  size_t write(const char* text) { return text == nullptr ? 0 : write(text, strlen(text)); }
  size_t write(const char* buffer, size_t size) {
    return write(reinterpret_cast<const uint8_t*>(buffer), size);
  }
  virtual int availableForWrite() { return 0; }
  virtual void flush() {}
  int getWriteError() const { return write_error_; }
  void clearWriteError() { write_error_ = 0; }

  size_t print(const __FlashStringHelper* text);
  size_t print(const String& text);
  size_t print(const char* text);
  size_t print(char c);
  size_t print(unsigned char value, int base = DEC);
  size_t print(int value, int base = DEC);
  size_t print(unsigned int value, int base = DEC);
  size_t print(long value, int base = DEC);
  size_t print(unsigned long value, int base = DEC);
  size_t print(long long value, int base = DEC);
  size_t print(unsigned long long value, int base = DEC);
  size_t print(double value, int digits = 2);
  size_t print(const Printable& p) { return p.printTo(*this); }

  size_t println();
  template <typename T>
  size_t println(const T& value) {
    const size_t n = print(value);
    return n + println();
  }
  template <typename T>
  size_t println(const T& value, int base_or_digits) {
    const size_t n = print(value, base_or_digits);
    return n + println();
  }
  size_t printf(const char* format, ...) __attribute__((format(printf, 2, 3)));

 protected:
  void setWriteError(int error = 1) { write_error_ = error; }

 private:
  size_t PrintNumber(unsigned long long value, int base, bool negative);
  int write_error_ = 0;
};

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_PRINT_H_
