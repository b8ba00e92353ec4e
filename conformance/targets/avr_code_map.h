// Which of an AVR firmware's instructions ran, and which way each went: one byte
// per flash word, bit 0 set when the instruction at that word fell through to
// the next one, bit 1 when it went anywhere else (a branch or skip taken, a
// jump, call or return). Its summary counts the firmware's static control-flow
// edges (each instruction's fall-through or taken outcome; a conditional
// branch or skip has both), how many of them the runs took, and names the
// functions the runs never entered (CodeCoverage, targets/target.h).
#ifndef MOCO_CONFORMANCE_TARGETS_AVR_CODE_MAP_H_
#define MOCO_CONFORMANCE_TARGETS_AVR_CODE_MAP_H_

#include <cstdint>
#include <span>
#include <vector>

#include "conformance/targets/avr_elf.h"
#include "conformance/targets/avr_stack.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

class AvrCodeMap {
 public:
  // Decodes the image's instruction lengths (flash bytes [0, code_end)).
  void Prepare(const avr_t* avr, uint32_t code_end);
  // One byte per flash word of the image.
  size_t bytes() const { return lengths_.size(); }

  // Marks the instruction that ran at `pc_before` (byte address): where it
  // went is avr->pc now, or, when it was interrupted right after
  // (`interrupted`), the return address the interrupt pushed.
  void Record(uint8_t* map, uint32_t pc_before, const avr_t* avr, bool interrupted) const {
    const uint32_t word = pc_before >> 1;
    if (word >= lengths_.size()) return;
    const uint32_t next = pc_before + lengths_[word];
    const uint32_t went = interrupted ? avr_stack::Pushed(avr, avr_stack::StackPointer(avr) + 1) * 2
                                      : static_cast<uint32_t>(avr->pc);
    map[word] |= went == next ? uint8_t{1} : uint8_t{2};
  }

  // Over the functions `symbols` size (a linear sweep of each).
  CodeCoverage Summarise(std::span<const uint8_t> map, const AvrSymbols& symbols) const;

 private:
  std::vector<uint8_t> lengths_;  // per flash word: 2 or 4 (as if an instruction started there)
  std::vector<uint16_t> words_;   // the image's words
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_AVR_CODE_MAP_H_
