// The AVR code map (see avr_code_map.h). Opcodes from the AVR Instruction Set
// Manual: the 32-bit ones are JMP 1001 010k kkkk 110k, CALL 1001 010k kkkk
// 111k, LDS 1001 000d dddd 0000 and STS 1001 001d dddd 0000; the conditional
// ones BRBS/BRBC 1111 0xkk kkkk ksss, SBRC/SBRS 1111 11xr rrrr 0bbb, CPSE 0001
// 00rd dddd rrrr, SBIC/SBIS 1001 1x01 AAAA Abbb.
#include "conformance/targets/avr_code_map.h"

#include <algorithm>

extern "C" {
#include "sim_avr.h"
}

namespace moco::conformance {
namespace {

bool IsLong(uint16_t w) { return (w & 0xFE0C) == 0x940C || (w & 0xFC0F) == 0x9000; }

bool IsConditional(uint16_t w) {
  return (w & 0xF800) == 0xF000 || (w & 0xFC08) == 0xFC00 || (w & 0xFC00) == 0x1000 ||
         (w & 0xFD00) == 0x9900;
}

}  // namespace

void AvrCodeMap::Prepare(const avr_t* avr, uint32_t code_end) {
  const uint32_t words = std::min<uint32_t>(code_end, avr->flashend + 1) / 2;
  words_.resize(words);
  lengths_.resize(words);
  for (uint32_t i = 0; i < words; ++i) {
    words_[i] = static_cast<uint16_t>(avr->flash[2 * i] | (avr->flash[2 * i + 1] << 8));
    lengths_[i] = IsLong(words_[i]) ? 4 : 2;
  }
}

CodeCoverage AvrCodeMap::Summarise(std::span<const uint8_t> map, const AvrSymbols& symbols) const {
  CodeCoverage c;
  std::vector<bool> counted(words_.size(), false);  // aliases share their code
  for (const AvrSymbols::Symbol& f : symbols.all()) {
    if (f.size == 0 || f.address / 2 >= words_.size()) continue;
    ++c.functions;
    const bool entered = f.address / 2 < map.size() && map[f.address / 2] != 0;
    if (!entered) c.never_entered.push_back(f.name);
    const uint32_t end =
        std::min<uint32_t>((f.address + f.size) / 2, static_cast<uint32_t>(words_.size()));
    for (uint32_t w = f.address / 2; w < end; w += lengths_[w] / 2) {
      if (counted[w]) continue;
      counted[w] = true;
      const uint8_t bits = w < map.size() ? map[w] : 0;
      ++c.instructions;
      c.instructions_reached += bits != 0 ? 1 : 0;
      if (IsConditional(words_[w])) {
        c.edges += 2;
        c.edges_reached += static_cast<size_t>((bits & 1) + ((bits >> 1) & 1));
      } else {
        c.edges += 1;
        c.edges_reached += bits != 0 ? 1 : 0;
      }
    }
  }
  return c;
}

}  // namespace moco::conformance
