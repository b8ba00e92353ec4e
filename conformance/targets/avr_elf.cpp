// An AVR ELF's header check and code symbols (see avr_elf.h).
#include "conformance/targets/avr_elf.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "base/file_io.h"

namespace moco::conformance {
namespace {

// ELF32 offsets and values (System V gABI).
constexpr size_t kHeaderBytes = 52;
constexpr size_t kSectionHeaderBytes = 40;
constexpr size_t kSymbolBytes = 16;
constexpr uint32_t kShtSymtab = 2;
constexpr uint32_t kShfExecInstr = 0x4;
constexpr unsigned kSttNotype = 0, kSttFunc = 2;
constexpr uint16_t kShnUndef = 0, kShnLoreserve = 0xff00;
// A symbol table larger than this is no AVR firmware's (a 256 KiB flash holds
// far fewer symbols); reading stops there.
constexpr uint32_t kMaxSymtabBytes = 64u << 20;
// An AVR image with its debug information is a few MiB; the same bound as a
// certificate's firmware digest (docs/certificates.md).
constexpr size_t kMaxElfBytes = size_t{64} << 20;

uint16_t U16(const std::string& b, size_t at) {
  return static_cast<uint16_t>(static_cast<uint8_t>(b[at]) |
                               (static_cast<uint8_t>(b[at + 1]) << 8));
}
uint32_t U32(const std::string& b, size_t at) {
  return static_cast<uint32_t>(U16(b, at)) | (static_cast<uint32_t>(U16(b, at + 2)) << 16);
}

}  // namespace

std::string CheckAvrElf(const std::string& path) {
  // Only a regular file is opened: a FIFO or device would block or never end.
  std::error_code ec;
  const auto kind = std::filesystem::status(path, ec).type();
  if (kind != std::filesystem::file_type::regular &&
      kind != std::filesystem::file_type::not_found) {
    return "not a regular file";
  }
  std::ifstream in(path, std::ios::binary);
  unsigned char h[20] = {};
  if (!in.read(reinterpret_cast<char*>(h), sizeof h)) return "too short for an ELF";
  if (h[0] != 0x7f || h[1] != 'E' || h[2] != 'L' || h[3] != 'F') return "not an ELF file";
  constexpr unsigned kElfClass32 = 1, kElfDataLsb = 1, kMachineAvr = 83;
  const unsigned machine = h[18] | (static_cast<unsigned>(h[19]) << 8);
  if (h[4] != kElfClass32 || h[5] != kElfDataLsb || machine != kMachineAvr) {
    return "an ELF for another machine (e_machine " + std::to_string(machine) + ", AVR is 83)";
  }
  return "";
}

AvrSymbols AvrSymbols::Read(const std::string& path, std::string* error) {
  AvrSymbols out;
  auto fail = [&](const std::string& what) {
    if (error != nullptr) *error = "cannot read the symbols of \"" + path + "\": " + what;
    return AvrSymbols();
  };
  if (const std::string problem = CheckAvrElf(path); !problem.empty()) return fail(problem);
  std::string b;
  if (auto problem = base::ReadFileBounded(path, &b, {.max_bytes = kMaxElfBytes})) {
    return fail(*problem);
  }
  if (b.size() < kHeaderBytes) return fail("too short for an ELF");
  const uint32_t shoff = U32(b, 0x20);
  const uint16_t shentsize = U16(b, 0x2E);
  const uint16_t shnum = U16(b, 0x30);
  if (shnum == 0) return out;  // no section headers: nothing to name
  if (shentsize != kSectionHeaderBytes ||
      uint64_t{shoff} + uint64_t{shnum} * kSectionHeaderBytes > b.size()) {
    return fail("its section headers lie outside the file");
  }
  auto section = [&](uint32_t i, uint32_t field) {
    return U32(b, shoff + i * kSectionHeaderBytes + field);
  };
  for (uint32_t s = 0; s < shnum; ++s) {
    if (section(s, 4) != kShtSymtab) continue;
    const uint32_t off = section(s, 16), size = section(s, 20), link = section(s, 24);
    if (size > kMaxSymtabBytes || uint64_t{off} + size > b.size() || link >= shnum) {
      return fail("its symbol table lies outside the file");
    }
    const uint32_t str_off = section(link, 16), str_size = section(link, 20);
    if (uint64_t{str_off} + str_size > b.size())
      return fail("its string table lies outside the file");
    for (uint32_t e = off; e + kSymbolBytes <= off + size; e += kSymbolBytes) {
      const unsigned type = static_cast<uint8_t>(b[e + 12]) & 0xF;
      const uint16_t shndx = U16(b, e + 14);
      if ((type != kSttFunc && type != kSttNotype) || shndx == kShnUndef ||
          shndx >= kShnLoreserve || shndx >= shnum || (section(shndx, 8) & kShfExecInstr) == 0) {
        continue;
      }
      const uint32_t name = U32(b, e);
      if (name == 0 || name >= str_size) continue;
      const size_t end = b.find('\0', str_off + name);
      if (end == std::string::npos || end > uint64_t{str_off} + str_size) continue;
      Symbol sym{U32(b, e + 4), U32(b, e + 8), b.substr(str_off + name, end - str_off - name)};
      // Local labels of the assembler (".L...") name no function.
      if (sym.name.empty() || sym.name[0] == '.') continue;
      out.symbols_.push_back(std::move(sym));
    }
  }
  std::sort(out.symbols_.begin(), out.symbols_.end(), [](const Symbol& x, const Symbol& y) {
    if (x.address != y.address) return x.address < y.address;
    if ((x.size != 0) != (y.size != 0)) return x.size != 0;
    return x.name < y.name;
  });
  return out;
}

std::optional<uint32_t> AvrSymbols::Address(std::string_view name) const {
  for (const Symbol& s : symbols_) {
    if (s.name == name) return s.address;
  }
  return std::nullopt;
}

const AvrSymbols::Symbol* AvrSymbols::At(uint32_t pc) const {
  auto it = std::upper_bound(symbols_.begin(), symbols_.end(), pc,
                             [](uint32_t v, const Symbol& s) { return v < s.address; });
  if (it == symbols_.begin()) return nullptr;
  // Of the symbols at the nearest address at or below pc, the sized one (first).
  --it;
  while (it != symbols_.begin() && std::prev(it)->address == it->address) --it;
  // Past a sized symbol's end lies padding or code no symbol names; past the
  // last symbol, when it has no size (the linker's _etext), no code at all.
  if (it->size != 0 && pc >= it->address + it->size) return nullptr;
  if (it->size == 0 && pc != it->address &&
      std::none_of(std::next(it), symbols_.end(),
                   [&](const Symbol& later) { return later.address > it->address; })) {
    return nullptr;
  }
  return &*it;
}

std::string AvrSymbols::Describe(uint32_t pc) const {
  char text[32];
  std::snprintf(text, sizeof text, "0x%04x", static_cast<unsigned>(pc));
  std::string out = text;
  if (const Symbol* s = At(pc)) {
    out += " (" + s->name;
    if (pc != s->address) {
      std::snprintf(text, sizeof text, "+0x%x", static_cast<unsigned>(pc - s->address));
      out += text;
    }
    out += ")";
  }
  return out;
}

}  // namespace moco::conformance
