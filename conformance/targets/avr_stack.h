// The AVR stack as simavr's core holds it, read one way by the simavr target
// and its oracles (avr_faults, avr_code_map): the stack pointer in the data
// space's SPL/SPH (0x5D/0x5E on every ATmega), and the return address a call
// or an interrupt's entry pushed (a word address, one byte at a time, low
// byte first, at SP and downwards: its highest byte at the lowest address,
// the push's slot, SP + 1 afterwards; 2 bytes, 3 on a core with a 22-bit PC).
#ifndef MOCO_CONFORMANCE_TARGETS_AVR_STACK_H_
#define MOCO_CONFORMANCE_TARGETS_AVR_STACK_H_

#include <cstdint>

extern "C" {
#include "sim_avr.h"
}

namespace moco::conformance::avr_stack {

inline constexpr uint16_t kSpl = 0x5D;
inline constexpr uint16_t kSph = 0x5E;

// SP: the next free byte (the last push wrote at SP + 1).
inline uint32_t StackPointer(const avr_t* avr) {
  return avr->data[kSpl] | (static_cast<uint32_t>(avr->data[kSph]) << 8);
}

// The return address (a word address) pushed at `slot`.
inline uint32_t Pushed(const avr_t* avr, uint32_t slot) {
  const uint8_t* b = &avr->data[slot];
  return avr->address_size == 3 ? (uint32_t{b[0]} << 16) | (uint32_t{b[1]} << 8) | b[2]
                                : (uint32_t{b[0]} << 8) | b[1];
}

}  // namespace moco::conformance::avr_stack

#endif  // MOCO_CONFORMANCE_TARGETS_AVR_STACK_H_
