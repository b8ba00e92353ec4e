// What the simavr target reads of an AVR ELF itself, besides what simavr loads:
// that it is one (simavr 1.6 crashes on ELFs for other machines), and its code
// symbols, to name the function a program counter is in (findings, hangs,
// backtraces) and to find the libgcc routines a fault oracle watches (the
// divisions). ELF32, little-endian, as avr-gcc links (System V gABI, "Sections",
// "Symbol Table").
#ifndef MOCO_CONFORMANCE_TARGETS_AVR_ELF_H_
#define MOCO_CONFORMANCE_TARGETS_AVR_ELF_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace moco::conformance {

// Checks the ELF header: a problem ("not a regular file", "not an ELF file",
// "an ELF for another machine ..."), or empty for an AVR ELF.
std::string CheckAvrElf(const std::string& path);

// The code symbols of an AVR ELF (.symtab entries of STT_FUNC or STT_NOTYPE in an
// executable section): byte addresses in flash, as simavr's avr->pc.
class AvrSymbols {
 public:
  struct Symbol {
    uint32_t address = 0;  // byte address in flash
    uint32_t size = 0;     // 0 when the symbol gives none (assembler labels)
    std::string name;
  };

  // Reads `path`'s symbol table. A stripped ELF gives no symbols and no error;
  // an unreadable or malformed one gives the problem in `*error` (may be null).
  static AvrSymbols Read(const std::string& path, std::string* error);

  bool empty() const { return symbols_.empty(); }
  // Every code symbol, by address.
  const std::vector<Symbol>& all() const { return symbols_; }
  size_t size() const { return symbols_.size(); }
  // The address of the code symbol `name`, or nullopt.
  std::optional<uint32_t> Address(std::string_view name) const;
  // The symbol `pc` lies in: the last one at or below it, within its size when
  // it has one. nullptr when none does.
  const Symbol* At(uint32_t pc) const;
  // "0x01a4 (HandleLine+0x1c)", or "0x01a4" where no symbol covers `pc`.
  std::string Describe(uint32_t pc) const;

 private:
  std::vector<Symbol> symbols_;  // by address; of equal addresses, the sized one first
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_AVR_ELF_H_
