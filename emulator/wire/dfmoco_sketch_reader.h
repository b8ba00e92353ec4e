// How the DFMoco sketch itself reads a host line (FACTS.md "DFMoco"): its
// processUserMessage state machine, one byte at a time, which is more lenient
// than ParseHostLine's reading and is what a real sketch answers to.
//
// The machine, as the sketch has it from 1.2.x to 2.0.0:
//  - The first byte of a line (other than '\r' or '\n') is taken; the second
//    must complete one of the known two-letter words with it, else the pair is
//    dropped and the next byte starts over (so "xmm 1 2" is never a command).
//  - hi, ms, sa and go take no arguments: every byte after the word is
//    ignored up to the line end.
//  - For the other words, an argument starts where a digit or '-' follows a
//    space; '-' sets the sign. Every later digit is appended (value * 10 +
//    digit, wrapping in 32 bits as the AVR does); any other byte but ' ' and
//    '\r' is ignored. A ' ' or '\r' right after a digit applies the sign;
//    '\r' ends the arguments. So "--5" reads -5, "99999999999" wraps to
//    1215752191, "x" is no argument at all and "5x" reads 5.
//  - The 40th argument answers `error: too many args` at once and the
//    command is dropped.
// Reading: a digit before the first argument would make the sketch write in
// front of its argument array (undefined there); the line is dropped.
#ifndef MOCO_WIRE_DFMOCO_SKETCH_READER_H_
#define MOCO_WIRE_DFMOCO_SKETCH_READER_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace moco::dfmoco {

struct SketchReading {
  enum class Kind : uint8_t {
    kNothing,      // no command: the sketch answers nothing
    kCommand,      // `word` with `args`
    kTooManyArgs,  // `error: too many args`, and nothing else
  };
  Kind kind = Kind::kNothing;
  std::string word;  // the two letters
  std::vector<int32_t> args;

  // The command as a canonical line ("mm 1 -5") that ParseHostLine reads the
  // same way; empty unless kind == kCommand.
  std::string CanonicalLine() const;
};

// `line` is one framed line without its "\r\n" (it may hold a bare '\r').
SketchReading ReadLineAsSketch(std::string_view line);

}  // namespace moco::dfmoco

#endif  // MOCO_WIRE_DFMOCO_SKETCH_READER_H_
