// The session mutator (see mutator.h): DMC frames (dmc-v2-protocol.txt
// "Message Format"), DFMoco lines (the sketch's grammar) and StackShot packets
// (stackshot-protocol.txt section 2) mutated per field, then repaired.
#include "conformance/fuzz/mutator.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <string_view>

#include "wire/dmc_constants.h"
#include "wire/dmc_frame.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::conformance {
namespace {

constexpr uint32_t kInteresting32[] = {
    0,       1,          2,          0x7f,       0x80,       0xff, 0x100, 0x7fff, 0x8000, 0xffff,
    0x10000, 0x7fffffff, 0x80000000, 0xfffffffe, 0xffffffff, 1000, 10000, 1048,   1036,   100000};

constexpr std::string_view kDfmWords[] = {"hi", "ms", "mm", "mp", "sm", "sa", "jm",
                                          "im", "pr", "zm", "np", "bf", "go", "mp *"};
constexpr std::string_view kDfmNumbers[] = {
    "0",    "1",     "-1",    "2",          "4",           "8",          "9",
    "100",  "20000", "40000", "2147483647", "-2147483648", "2147483648", "99999999999",
    "1000", "-0",    "+5",    "0x10",       "1e3",         "3.5"};

// The frame's ID, Type and data section when `m` starts with a whole DMC header.
bool DmcParts(const wire::Bytes& m, uint32_t& id, uint16_t& type, wire::Bytes& data) {
  const auto h = dmc::PeekHeader(m);
  if (!h) return false;
  id = h->id;
  type = h->type;
  const size_t have = m.size() - dmc::kHeaderSize;
  // Data runs to the declared length, or to what is there before the check bytes.
  const size_t n =
      std::min<size_t>(h->length, have >= dmc::kCheckSize ? have - dmc::kCheckSize : 0);
  data.assign(m.begin() + dmc::kHeaderSize,
              m.begin() + static_cast<ptrdiff_t>(dmc::kHeaderSize + n));
  return true;
}

}  // namespace

SessionMutator::SessionMutator(Protocol protocol, uint64_t seed)
    : protocol_(protocol), state_(seed ^ 0x9e3779b97f4a7c15ULL) {}

uint64_t SessionMutator::Next() {
  uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

uint64_t SessionMutator::Below(uint64_t n) { return Next() % n; }

bool SessionMutator::Chance(uint32_t percent) { return Below(100) < percent; }

void SessionMutator::Mutate(Messages& messages, const std::vector<Messages>& donors) {
  last_.clear();
  const uint64_t rounds = 1 + Below(4);
  for (uint64_t r = 0; r < rounds; ++r) MutateOne(messages, donors);
  if (messages.size() > kMaxMessages) messages.resize(kMaxMessages);
}

void SessionMutator::MutateDataBytes(wire::Bytes& data) {
  switch (Below(6)) {
    case 0:  // flip one bit
      if (!data.empty()) data[Below(data.size())] ^= static_cast<uint8_t>(1u << Below(8));
      last_.push_back("bit-flip");
      break;
    case 1: {  // an interesting value, 1, 2 or 4 bytes wide, little-endian
      const uint32_t v = kInteresting32[Below(std::size(kInteresting32))];
      const size_t width = size_t{1} << Below(3);
      if (data.size() >= width) {
        const size_t at = Below(data.size() - width + 1);
        for (size_t k = 0; k < width; ++k) data[at + k] = static_cast<uint8_t>(v >> (8 * k));
      }
      last_.push_back("field-value");
      break;
    }
    case 2:  // a random byte
      if (!data.empty()) data[Below(data.size())] = static_cast<uint8_t>(Next());
      last_.push_back("byte");
      break;
    case 3:  // truncate
      if (!data.empty()) data.resize(Below(data.size()));
      last_.push_back("truncate");
      break;
    case 4: {  // extend
      const size_t n = 1 + Below(Chance(10) ? 1100 : 8);
      for (size_t k = 0; k < n; ++k) data.push_back(static_cast<uint8_t>(Next()));
      last_.push_back("extend");
      break;
    }
    default:  // negate an int32 at an aligned offset
      if (data.size() >= 4) {
        const size_t at = 4 * Below(data.size() / 4);
        uint32_t v = 0;
        std::memcpy(&v, &data[at], 4);
        v = ~v + 1;
        std::memcpy(&data[at], &v, 4);
      }
      last_.push_back("negate");
      break;
  }
}

void SessionMutator::MutateDmc(wire::Bytes& m) {
  uint32_t id = 0;
  uint16_t type = 0;
  wire::Bytes data;
  if (!DmcParts(m, id, type, data)) {
    if (!m.empty()) m[Below(m.size())] ^= static_cast<uint8_t>(1u << Below(8));
    last_.push_back("noise-flip");
    return;
  }
  if (Chance(15)) {
    // Another message type, so the data meets a different decoder.
    static constexpr uint16_t kTypes[] = {
        0x0001, 0x0020, 0x0021, 0x0022, 0x0023, 0x0030, 0x0031, 0x0032, 0x0033, 0x0034,
        0x0035, 0x0036, 0x0037, 0x0038, 0x0039, 0x003a, 0x0100, 0x0101, 0x0102, 0x0103,
        0x0104, 0x0110, 0x0111, 0x0112, 0x0113, 0x0114, 0x0115, 0x0116, 0x0120, 0x0200,
        0x0201, 0x0202, 0x0203, 0x0204, 0x0205, 0x0206, 0x0207, 0x8001, 0x0400, 0xffff};
    type = kTypes[Below(std::size(kTypes))];
    last_.push_back("type");
  } else {
    MutateDataBytes(data);
  }
  m.clear();
  dmc::EncodeFrame(id, type, data, m);
  if (Chance(3)) {
    // A wrong checksum on purpose: the device must answer ERR_CHECKSUM.
    m.back() = static_cast<uint8_t>(m.back() ^ 0x5a);
    last_.push_back("bad-checksum");
  }
}

void SessionMutator::MutateStackshot(wire::Bytes& m) {
  auto peeked = stackshot::PeekHostPacket(m);
  if (!peeked) {
    if (!m.empty()) m[Below(m.size())] ^= static_cast<uint8_t>(1u << Below(8));
    last_.push_back("noise-flip");
    return;
  }
  stackshot::Packet& p = *peeked;
  switch (Below(5)) {
    case 0: {
      const auto all = stackshot::AllCommands();
      p.command =
          Chance(80) && !all.empty() ? all[Below(all.size())].id : static_cast<uint16_t>(Next());
      last_.push_back("command");
      break;
    }
    case 1:
      p.action = static_cast<uint8_t>(Below(16));
      last_.push_back("action");
      break;
    case 2:
      p.axis = static_cast<uint8_t>(Below(4));
      p.sub_item = Chance(20);
      last_.push_back("axis");
      break;
    default:
      MutateDataBytes(p.data);
      break;
  }
  if (p.data.size() > stackshot::kMaxDataBytes) p.data.resize(stackshot::kMaxDataBytes);
  stackshot::Seal(p, stackshot::kDefaultChecksum);
  m.clear();
  stackshot::EncodePacket(p, m);
}

void SessionMutator::MutateDfmoco(wire::Bytes& m) {
  std::string line(m.begin(), m.end());
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
  std::vector<std::string> tokens;
  size_t i = 0;
  while (i < line.size()) {
    const size_t j = line.find(' ', i);
    tokens.push_back(line.substr(i, j == std::string::npos ? std::string::npos : j - i));
    i = j == std::string::npos ? line.size() : j + 1;
  }
  switch (Below(7)) {
    case 0:  // a number replaced
      if (tokens.size() > 1) {
        tokens[1 + Below(tokens.size() - 1)] = kDfmNumbers[Below(std::size(kDfmNumbers))];
      } else {
        tokens.emplace_back(kDfmNumbers[Below(std::size(kDfmNumbers))]);
      }
      last_.push_back("number");
      break;
    case 1:  // the word replaced
      if (tokens.empty()) tokens.emplace_back();
      tokens[0] = kDfmWords[Below(std::size(kDfmWords))];
      last_.push_back("word");
      break;
    case 2:  // an argument dropped or added
      if (tokens.size() > 1 && Chance(50)) {
        tokens.erase(tokens.begin() + 1 + static_cast<ptrdiff_t>(Below(tokens.size() - 1)));
      } else {
        const size_t n = Chance(10) ? 40 : 1;
        for (size_t k = 0; k < n; ++k) tokens.emplace_back(std::to_string(Below(20)));
      }
      last_.push_back("arity");
      break;
    case 3:  // a random byte, maybe not ASCII
      if (!line.empty()) {
        line[Below(line.size())] = static_cast<char>(Next());
        tokens = {line};
      }
      last_.push_back("byte");
      break;
    case 4:  // whitespace games
      tokens = {Chance(50) ? "  " + line : line + "   "};
      last_.push_back("spaces");
      break;
    case 5:  // the line end dropped: runs into the next line
      m.assign(line.begin(), line.end());
      last_.push_back("no-line-end");
      return;
    default: {  // a long line
      std::string s = line;
      while (s.size() < kMaxDfmocoLine) s += " 7";
      tokens = {s};
      last_.push_back("long-line");
      break;
    }
  }
  std::string out;
  for (size_t k = 0; k < tokens.size(); ++k) out += (k ? " " : "") + tokens[k];
  if (out.size() > kMaxDfmocoLine) out.resize(kMaxDfmocoLine);
  out += Chance(90) ? "\r\n" : "\n";
  m.assign(out.begin(), out.end());
}

void SessionMutator::MutateOne(Messages& messages, const std::vector<Messages>& donors) {
  if (messages.empty()) messages.push_back(wire::Info(protocol_).greeting());
  const uint64_t pick = Below(100);
  const size_t at = Below(messages.size());
  if (pick < 60) {
    switch (protocol_) {
      case Protocol::kDmc:
        MutateDmc(messages[at]);
        break;
      case Protocol::kStackshot:
        MutateStackshot(messages[at]);
        break;
      case Protocol::kDfmoco:
      case Protocol::kStackshotDfmoco:
        MutateDfmoco(messages[at]);
        break;
    }
  } else if (pick < 70) {  // duplicate
    messages.insert(messages.begin() + static_cast<ptrdiff_t>(at), messages[at]);
    last_.push_back("duplicate");
  } else if (pick < 78) {  // delete
    if (messages.size() > 1) messages.erase(messages.begin() + static_cast<ptrdiff_t>(at));
    last_.push_back("delete");
  } else if (pick < 85) {  // swap two
    std::swap(messages[at], messages[Below(messages.size())]);
    last_.push_back("swap");
  } else if (pick < 95) {  // splice a message from another session (or this one)
    const Messages* from = &messages;
    if (!donors.empty()) {
      const Messages& d = donors[Below(donors.size())];
      if (!d.empty()) from = &d;
    }
    wire::Bytes copy = (*from)[Below(from->size())];
    messages.insert(messages.begin() + static_cast<ptrdiff_t>(Below(messages.size() + 1)),
                    std::move(copy));
    last_.push_back("splice");
  } else {  // cut a message short in the middle of the stream (framing resync)
    wire::Bytes& m = messages[at];
    if (m.size() > 1) m.resize(1 + Below(m.size() - 1));
    last_.push_back("cut");
  }
}

}  // namespace moco::conformance
