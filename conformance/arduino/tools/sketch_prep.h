// Arduino sketch preprocessing as the Arduino builder does it (Arduino CLI "Sketch build
// process": .ino concatenation, automatic prototypes, #line mapping), so a sketch folder's
// .ino files compile as one C++ translation unit against a host Arduino core.
//
// The output is `#include <Arduino.h>`, then every file preceded by `#line 1 "<name>"`, with
// one block of generated prototypes placed at file scope just before the first function
// definition. A prototype is generated for each function defined at brace depth 0 unless it
// is a template, an operator, a qualified (member) definition, has default arguments, has no
// return type (a macro such as `ISR(vec) {`), was declared with the same parameter text before
// the block, or mentions a type that is only declared between the block and the definition.
// A definition inside #if/#ifdef/#else groups gets its prototype inside the same chain of
// conditions; `#if 0` groups are skipped. Only text is inserted: every line of the sketch is
// kept, in order. Time and memory are linear in the size of the sketch.
#ifndef MOCO_CONFORMANCE_ARDUINO_TOOLS_SKETCH_PREP_H_
#define MOCO_CONFORMANCE_ARDUINO_TOOLS_SKETCH_PREP_H_

#include <cstddef>
#include <string>
#include <variant>
#include <vector>

namespace moco::arduino {

// One .ino file of a sketch.
struct SketchFile {
  std::string name;  // as it should appear in #line, e.g. "/abs/path/Blink.ino"
  std::string text;
};

// Alternatives of PrepareSketch's result; both hold a std::string, so test `index()`.
inline constexpr std::size_t kPreparedSource = 0;
inline constexpr std::size_t kPrepareError = 1;

// The sketch's .ino files -> one C++ source (alternative kPreparedSource), or a message
// "<file>:<line>: <what is wrong>" (alternative kPrepareError) for an unterminated comment,
// string or character literal, a bad raw string, a brace that is never closed or a '}'
// without '{' (brace balance is only judged when no brace sits inside #if groups; otherwise
// the compiler decides), or an empty file list.
// REQUIRES: `files` in the Arduino order (see OrderInoFiles). A leading UTF-8 byte order mark
// of each file is dropped.
std::variant<std::string, std::string> PrepareSketch(const std::vector<SketchFile>& files);

// Orders .ino file names as the Arduino builder does: the main file first, the rest in byte
// order. A name is the main file when it equals `main_name` ("Blink.ino", the folder's name +
// .ino) or ends with "/" + `main_name`; without one, all names are sorted.
std::vector<std::string> OrderInoFiles(std::vector<std::string> names,
                                       const std::string& main_name);

}  // namespace moco::arduino

#endif  // MOCO_CONFORMANCE_ARDUINO_TOOLS_SKETCH_PREP_H_
