// The DFMoco sketch's byte-at-a-time line reader; see dfmoco_sketch_reader.h.
#include "wire/dfmoco_sketch_reader.h"

#include <array>
#include <cstddef>

#include "wire/dfmoco.h"

namespace moco::dfmoco {
namespace {

enum class State : uint8_t { kStart, kWord, kArgs, kError, kDone };

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// The words the sketch knows, and whether arguments follow.
struct Word {
  char first;
  char second;
  bool takes_args;
};
constexpr std::array<Word, 13> kWords = {{{'h', 'i', false},
                                          {'m', 's', false},
                                          {'s', 'a', false},
                                          {'m', 'm', true},
                                          {'n', 'p', true},
                                          {'m', 'p', true},
                                          {'z', 'm', true},
                                          {'s', 'm', true},
                                          {'p', 'r', true},
                                          {'b', 'f', true},
                                          {'g', 'o', false},
                                          {'j', 'm', true},
                                          {'i', 'm', true}}};

// 32-bit wrap-around arithmetic, as on the AVR.
int32_t Wrap(uint32_t v) { return static_cast<int32_t>(v); }

}  // namespace

std::string SketchReading::CanonicalLine() const {
  if (kind != Kind::kCommand) return {};
  std::string out = word;
  for (const int32_t a : args) out += " " + std::to_string(a);
  return out;
}

SketchReading ReadLineAsSketch(std::string_view line) {
  SketchReading r;
  State state = State::kStart;
  char last = '\n';  // the byte before the line: the previous line's '\n'
  int32_t sign = 1;
  bool stray_digit = false;
  auto feed = [&](char c) {
    switch (state) {
      case State::kStart:
        if (c != '\r' && c != '\n') {
          state = State::kWord;
          sign = 1;
          r.word.clear();
          r.args.clear();
          stray_digit = false;
        }
        break;
      case State::kWord: {
        state = State::kStart;
        for (const Word& w : kWords) {
          if (w.first == last && w.second == c) {
            r.word = {w.first, w.second};
            state = w.takes_args ? State::kArgs : State::kDone;
            break;
          }
        }
        break;
      }
      case State::kArgs:
        if ((IsDigit(c) || c == '-') && last == ' ') {
          if (r.args.size() + 1 >= kMaxArgs) {
            r.kind = SketchReading::Kind::kTooManyArgs;
            state = State::kError;
            break;
          }
          sign = c == '-' ? -1 : 1;
          r.args.push_back(c == '-' ? 0 : c - '0');
        } else if (IsDigit(c)) {
          if (r.args.empty()) {
            stray_digit = true;
          } else {
            const auto v = static_cast<uint32_t>(r.args.back());
            r.args.back() = Wrap(v * 10u + static_cast<uint32_t>(c - '0'));
          }
        } else if (c == ' ' || c == '\r') {
          if (IsDigit(last) && !r.args.empty() && sign < 0) {
            r.args.back() = Wrap(0u - static_cast<uint32_t>(r.args.back()));
          }
          if (c == '\r') state = State::kDone;
        }
        break;
      case State::kError:
        state = State::kDone;
        break;
      case State::kDone:
        break;
    }
    last = c;
  };
  for (const char c : line) feed(c);
  feed('\r');
  // The '\n' after '\r' completes whatever reached kDone.
  if (r.kind == SketchReading::Kind::kTooManyArgs) {
    r.word.clear();
    r.args.clear();
    return r;
  }
  if (state == State::kDone && !r.word.empty() && !stray_digit) {
    r.kind = SketchReading::Kind::kCommand;
  } else {
    r.word.clear();
    r.args.clear();
  }
  return r;
}

}  // namespace moco::dfmoco
