// An AVR's I/O ports on the host core, for boards whose file maps them
// (MOCO_API_AVR_PORTS): PORTB, PORTC, PORTD as 8-bit registers whose writes
// are pin edges through the board's port map, all changed bits at one instant;
// DDRx kept as written; PINx reading the levels. _BV() and the bit names.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_IO_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_IO_H_

#include <stdint.h>

#include "moco_core.h"

#define _BV(bit) (1u << (bit))

#ifdef MOCO_API_AVR_PORTS
namespace moco::arduino {

// One 8-bit output port register.
class PortRegister {
 public:
  explicit constexpr PortRegister(char port) : port_(port) {}
  operator uint8_t() const { return value_; }
  PortRegister& operator=(unsigned value) {
    const uint8_t before = value_;
    value_ = static_cast<uint8_t>(value);
    PortWrite(port_, before, value_);
    return *this;
  }
  PortRegister& operator|=(unsigned bits) { return *this = value_ | bits; }
  PortRegister& operator&=(unsigned bits) { return *this = value_ & bits; }
  PortRegister& operator^=(unsigned bits) { return *this = value_ ^ bits; }

 private:
  char port_;
  uint8_t value_ = 0;
};

// A plain register: kept as written (a data direction register).
class PlainRegister {
 public:
  operator uint8_t() const { return value_; }
  PlainRegister& operator=(unsigned value) {
    value_ = static_cast<uint8_t>(value);
    return *this;
  }
  PlainRegister& operator|=(unsigned bits) { return *this = value_ | bits; }
  PlainRegister& operator&=(unsigned bits) { return *this = value_ & bits; }

 private:
  uint8_t value_ = 0;
};

inline PortRegister& PortB() {
  static PortRegister r('B');
  return r;
}
inline PortRegister& PortC() {
  static PortRegister r('C');
  return r;
}
inline PortRegister& PortD() {
  static PortRegister r('D');
  return r;
}
inline PlainRegister& Ddr(int which) {
  static PlainRegister r[3];
  return r[which];
}

}  // namespace moco::arduino

#define PORTB (moco::arduino::PortB())
#define PORTC (moco::arduino::PortC())
#define PORTD (moco::arduino::PortD())
#define DDRB (moco::arduino::Ddr(0))
#define DDRC (moco::arduino::Ddr(1))
#define DDRD (moco::arduino::Ddr(2))
#define PINB ((uint8_t)moco::arduino::PortB())
#define PINC ((uint8_t)moco::arduino::PortC())
#define PIND ((uint8_t)moco::arduino::PortD())

#define PB0 0
#define PB1 1
#define PB2 2
#define PB3 3
#define PB4 4
#define PB5 5
#define PB6 6
#define PB7 7
#define PC0 0
#define PC1 1
#define PC2 2
#define PC3 3
#define PC4 4
#define PC5 5
#define PC6 6
#define PD0 0
#define PD1 1
#define PD2 2
#define PD3 3
#define PD4 4
#define PD5 5
#define PD6 6
#define PD7 7
#endif  // MOCO_API_AVR_PORTS

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_IO_H_
