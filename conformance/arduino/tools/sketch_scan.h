// The lexer of sketch preprocessing: .ino text -> the C++ tokens the prototype finder reads.
#ifndef MOCO_CONFORMANCE_ARDUINO_TOOLS_SKETCH_SCAN_H_
#define MOCO_CONFORMANCE_ARDUINO_TOOLS_SKETCH_SCAN_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/arduino/tools/sketch_prep.h"

namespace moco::arduino {

// What a token is. Blanks, backslash-newlines and comments yield no token.
enum class TokKind : uint8_t {
  kIdent,      // an identifier or keyword; '$' and bytes >= 0x80 are identifier characters
  kNumber,     // a preprocessing number: 1, 0x1F, 1.5e-3, 1'000, .5f
  kLiteral,    // a string or character literal with its prefix, raw strings included
  kPunct,      // an operator or punctuator: the longest multi-byte one that fits, else one byte
  kDirective,  // a whole preprocessor line from its '#' to (not including) its newline
};
// What a directive does to conditional compilation.
enum class DirKind : uint8_t {
  kOther,  // #define, #include, #pragma, ... (and a lone '#')
  kIf,     // #if, #ifdef, #ifndef
  kElse,   // #elif, #else, #elifdef, #elifndef
  kEndif,  // #endif
};

// One token: a byte range of one file's text, which holds continuations and comments for a
// kDirective.
struct SketchToken {
  size_t begin = 0;  // byte offsets into the file's text
  size_t end = 0;
  uint32_t file = 0;  // index of the file in the sketch
  uint32_t line = 0;  // 1-based line of `begin`
  TokKind kind = TokKind::kPunct;
  DirKind dir = DirKind::kOther;  // kOther unless kind is kDirective
};

// True when `word` is one of `words`.
inline bool OneOf(std::string_view word, std::initializer_list<std::string_view> words) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

// "<file>:<line>: <what>", the form of every error PrepareSketch reports.
std::string Located(std::string_view file, uint32_t line, std::string_view what);

// Appends the tokens of the sketch's files, one file after the other, to `tokens`; texts[i]
// is the text of files[i] (its name goes into messages; its own text is not read) and its
// tokens have `file` == i. An `#if 0` or `#if false` group (also via #elif, and across the
// end of a file, as in the concatenated source) yields only its opening directive and the
// #elif/#else/#endif that ends it: the text between, nested groups included, yields none.
// A '#' that is the first token of its line starts a directive.
// Returns "<name>:<line>: <what>" for an unterminated /* comment, or, outside `#if 0` groups
// and directives, for an unterminated string or character literal or raw string or a bad raw
// string delimiter (inside them a literal ends quietly at the end of its line); `tokens` then
// holds what was read before.
// REQUIRES: texts.size() == files.size(), fewer than 2^32 files and lines a file.
std::optional<std::string> ScanSketch(const std::vector<SketchFile>& files,
                                      const std::vector<std::string_view>& texts,
                                      std::vector<SketchToken>* tokens);

}  // namespace moco::arduino

#endif  // MOCO_CONFORMANCE_ARDUINO_TOOLS_SKETCH_SCAN_H_
