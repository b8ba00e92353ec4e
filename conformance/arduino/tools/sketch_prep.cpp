// Arduino sketch preprocessing (Arduino CLI "Sketch build process"): a file-scope walk over
// the sketch's tokens (sketch_scan.h) finds the function definitions that need prototypes,
// without running a compiler or ctags, and places the prototype block.
#include "conformance/arduino/tools/sketch_prep.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <variant>
#include <vector>

#include "conformance/arduino/tools/sketch_scan.h"

namespace moco::arduino {
namespace {

constexpr size_t kNone = static_cast<size_t>(-1);
// Longest text of #if/#elif/#else lines repeated around one prototype; a definition nested
// deeper than this gets no prototype, which keeps the output linear in the input.
constexpr size_t kMaxConditionBytes = 512;

bool IsKeyword(std::string_view word) {
  static const std::unordered_set<std::string_view> kKeywords = {
      "alignas",       "alignof",     "and",
      "and_eq",        "asm",         "auto",
      "bitand",        "bitor",       "bool",
      "break",         "case",        "catch",
      "char",          "char8_t",     "char16_t",
      "char32_t",      "class",       "compl",
      "concept",       "const",       "consteval",
      "constexpr",     "constinit",   "const_cast",
      "continue",      "co_await",    "co_return",
      "co_yield",      "decltype",    "default",
      "delete",        "do",          "double",
      "dynamic_cast",  "else",        "enum",
      "explicit",      "export",      "extern",
      "false",         "float",       "for",
      "friend",        "goto",        "if",
      "inline",        "int",         "long",
      "mutable",       "namespace",   "new",
      "noexcept",      "not",         "not_eq",
      "nullptr",       "operator",    "or",
      "or_eq",         "private",     "protected",
      "public",        "register",    "reinterpret_cast",
      "requires",      "return",      "short",
      "signed",        "sizeof",      "static",
      "static_assert", "static_cast", "struct",
      "switch",        "template",    "this",
      "thread_local",  "throw",       "true",
      "try",           "typedef",     "typeid",
      "typename",      "union",       "unsigned",
      "using",         "virtual",     "void",
      "volatile",      "wchar_t",     "while",
      "xor",           "xor_eq",      "_Static_assert"};
  return kKeywords.count(word) != 0;
}

// Names followed by a parenthesised group that belongs to a declaration's specifiers
// rather than being its parameter list.
bool IsAttributeLike(std::string_view word) {
  return OneOf(word, {"__attribute__", "__attribute", "__declspec", "alignas", "_Alignas",
                      "decltype", "__typeof__", "__typeof", "typeof", "__asm__", "__asm", "asm"});
}

// Words that may follow a free function's parameter list before its body.
bool IsTrailerWord(std::string_view word) {
  return OneOf(word, {"const", "volatile", "noexcept", "throw", "override", "final",
                      "__attribute__", "__attribute", "__asm__", "__asm", "asm"});
}

// Words of a declaration that say nothing about its type.
bool IsSpecifier(std::string_view word) {
  return OneOf(word,
               {"static", "inline", "extern", "constexpr", "consteval", "constinit", "virtual",
                "explicit", "register", "thread_local", "mutable", "const", "volatile", "__inline",
                "__inline__", "__forceinline", "__extension__", "_Noreturn"});
}

bool IsOpener(std::string_view s) { return s == "(" || s == "[" || s == "{"; }
bool IsCloser(std::string_view s) { return s == ")" || s == "]" || s == "}"; }
// A #line directive for `file`, with the name escaped as a string literal.
std::string LineDirective(uint32_t line, std::string_view file) {
  static constexpr char kOctal[] = "01234567";
  std::string out = "#line " + std::to_string(line) + " \"";
  for (const char c : file) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\\' || c == '"') {
      out += '\\';
      out += c;
    } else if (u < 0x20 || u == 0x7f) {
      out += '\\';
      out += kOctal[(u >> 6) & 7];
      out += kOctal[(u >> 3) & 7];
      out += kOctal[u & 7];
    } else {
      out += c;
    }
  }
  out += "\"\n";
  return out;
}

// Ends the last line of `out` so that what follows starts a new logical line: a trailing
// backslash-newline would splice the next line onto this one, so it gets an empty line.
void EndLine(std::string* out) {
  if (out->empty()) return;
  if (out->back() != '\n') out->push_back('\n');
  size_t k = out->size() - 1;
  if (k > 0 && (*out)[k - 1] == '\r') --k;
  if (k > 0 && (*out)[k - 1] == '\\') out->push_back('\n');
}

uint64_t HashMix(uint64_t hash, std::string_view text) {
  constexpr uint64_t kPrime = 1099511628211ull;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= kPrime;
  }
  hash ^= 0x100;  // line separator, outside the byte range
  return hash * kPrime;
}
// The shape of the tokens before a '{' or ';' at file scope.
struct Shape {
  bool function_like = false;  // [specifiers and type] name(parameters) [trailer]
  bool eligible = false;       // may be given a generated prototype
  size_t name = kNone;
  size_t lparen = kNone;
  size_t rparen = kNone;
};

struct Definition {
  size_t begin = 0;  // first token of the header
  size_t end = 0;    // the '{' that opens the body
  Shape shape;
  size_t cond_depth = 0;  // enclosing #if groups
  uint64_t cond_hash = 0;
  bool wrappable = false;  // its #if lines are short enough to repeat
  std::string cond_lines;  // the #if/#elif/#else lines that lead to it, for eligible ones
};

struct Declaration {
  size_t begin = 0;
  std::string key;  // name and parameter text without blanks
};

// Walks the tokens at file scope: finds definitions and declarations, tracks #if groups
// and the first declaration of each type name.
class Analyzer {
 public:
  Analyzer(const std::vector<SketchFile>& files, const std::vector<std::string_view>& texts,
           const std::vector<SketchToken>& tokens)
      : files_(files), texts_(texts), tokens_(tokens) {}

  // Returns an error for braces that certainly do not balance.
  std::optional<std::string> Run();

  struct Insertion {
    uint32_t file = 0;
    size_t offset = 0;
    std::string block;  // prototypes and the #line that resumes the sketch
  };
  // Where the prototype block goes and what it says; nullopt when no prototype is needed.
  std::optional<Insertion> BuildInsertion() const;

 private:
  struct CondFrame {
    size_t lines_begin = 0;
    int depth_at_if = 0;
    bool expr_at_if = false;
    int depth_after_first = -1;  // brace depth at the first #elif/#else, -1 before it
    bool expr_after_first = false;
  };

  std::string_view Text(size_t i) const {
    const SketchToken& t = tokens_[i];
    return texts_[t.file].substr(t.begin, t.end - t.begin);
  }
  std::string Locate(size_t i, std::string_view what) const {
    return Located(files_[tokens_[i].file].name, tokens_[i].line, what);
  }
  bool IsName(size_t i) const {
    return i < tokens_.size() && tokens_[i].kind == TokKind::kIdent && !IsKeyword(Text(i));
  }
  size_t MatchGroup(size_t open, size_t end) const;
  size_t SkipAngles(size_t open, size_t end) const;
  bool HasReturnType(size_t begin, size_t name) const;
  Shape ParseHeader(size_t begin, size_t end) const;
  std::string Key(const Shape& shape) const;
  uint64_t CondHash() const { return cond_hash_.empty() ? 0 : cond_hash_.back(); }
  size_t CondBytes() const { return cond_bytes_.empty() ? 0 : cond_bytes_.back(); }
  void Conditional(size_t i, int* depth, bool* expr_brace);
  void PushCondLine(size_t i);
  void NoteTypeName(size_t i, bool in_typedef);
  void NoteDefinition(size_t begin, size_t end);
  void NoteDeclaration(size_t begin, size_t end);
  bool UsesTypeDeclaredBetween(const Definition& def, size_t after) const;

  const std::vector<SketchFile>& files_;
  const std::vector<std::string_view>& texts_;
  const std::vector<SketchToken>& tokens_;
  std::vector<CondFrame> frames_;
  std::vector<size_t> cond_lines_;   // directive tokens of the open #if chains
  std::vector<uint64_t> cond_hash_;  // running hash of cond_lines_
  std::vector<size_t> cond_bytes_;   // running length of cond_lines_
  bool brace_in_conditional_ = false;
  std::vector<Definition> definitions_;
  std::vector<Declaration> declarations_;
  std::unordered_map<std::string_view, size_t> type_first_;  // type name -> first token
};

size_t Analyzer::MatchGroup(size_t open, size_t end) const {
  int depth = 0;
  for (size_t k = open; k < end; ++k) {
    if (tokens_[k].kind == TokKind::kDirective) return kNone;
    if (tokens_[k].kind != TokKind::kPunct) continue;
    const std::string_view s = Text(k);
    if (IsOpener(s)) {
      ++depth;
    } else if (IsCloser(s) && --depth == 0) {
      return k;
    }
  }
  return kNone;
}

size_t Analyzer::SkipAngles(size_t open, size_t end) const {
  int depth = 0;
  for (size_t k = open; k < end; ++k) {
    if (tokens_[k].kind == TokKind::kDirective) return kNone;
    const std::string_view s = Text(k);
    if (IsOpener(s)) {
      k = MatchGroup(k, end);
      if (k == kNone) return kNone;
      continue;
    }
    if (s == "<") {
      ++depth;
    } else if (s == ">" || s == ">>") {
      depth -= static_cast<int>(s.size());
      if (depth <= 0) return k + 1;
    }
  }
  return kNone;
}

bool Analyzer::HasReturnType(size_t begin, size_t name) const {
  bool has_type = false;
  for (size_t k = begin; k < name; ++k) {
    const std::string_view s = Text(k);
    if (s == "{") return false;  // a type defined in the return type
    if (IsOpener(s)) {           // attribute groups
      k = MatchGroup(k, name);
      if (k == kNone) return false;
      continue;
    }
    if (tokens_[k].kind != TokKind::kIdent) continue;
    if (OneOf(s, {"typedef", "using", "friend", "return", "template"})) return false;
    if (OneOf(s, {"decltype", "__typeof__", "__typeof", "typeof"}) ||
        (!IsSpecifier(s) && !IsAttributeLike(s))) {
      has_type = true;
    }
  }
  return has_type;
}

Shape Analyzer::ParseHeader(size_t begin, size_t end) const {
  Shape shape;
  bool is_template = false;
  size_t name = kNone;
  for (size_t j = begin; j < end;) {
    const SketchToken& t = tokens_[j];
    if (t.kind == TokKind::kDirective) return shape;
    const std::string_view s = Text(j);
    if (t.kind == TokKind::kIdent) {
      if (s == "operator") {  // a definition, but never given a prototype
        shape.function_like = true;
        return shape;
      }
      if (s == "template") {
        is_template = true;
        if (j + 1 < end && Text(j + 1) == "<") {
          j = SkipAngles(j + 1, end);
          if (j == kNone) return shape;
          continue;
        }
      }
    } else if (t.kind == TokKind::kPunct) {
      if (s == "=" || IsCloser(s)) return shape;
      if (s == "[" || s == "{") {
        j = MatchGroup(j, end);
        if (j == kNone) return shape;
        ++j;
        continue;
      }
      if (s == "(") {
        if (j == begin || tokens_[j - 1].kind != TokKind::kIdent) return shape;
        const std::string_view previous = Text(j - 1);
        const size_t close = MatchGroup(j, end);
        if (close == kNone) return shape;
        if (IsAttributeLike(previous)) {
          j = close + 1;
          continue;
        }
        if (IsKeyword(previous)) return shape;
        name = j - 1;
        shape.lparen = j;
        shape.rparen = close;
        break;
      }
    }
    ++j;
  }
  if (name == kNone) return shape;
  bool has_initializers = false;
  for (size_t k = shape.rparen + 1; k < end;) {
    const std::string_view s = Text(k);
    if (tokens_[k].kind == TokKind::kDirective) return shape;
    if (tokens_[k].kind == TokKind::kIdent && IsTrailerWord(s)) {
      if (k + 1 < end && Text(k + 1) == "(") {
        k = MatchGroup(k + 1, end);
        if (k == kNone) return shape;
      }
      ++k;
    } else if (s == "&" || s == "&&") {
      ++k;
    } else if (s == "[") {
      k = MatchGroup(k, end);
      if (k == kNone) return shape;
      ++k;
    } else if (s == "->" || s == ":") {  // trailing return type, constructor initializers
      has_initializers = s == ":";
      break;
    } else {
      return shape;
    }
  }
  shape.function_like = true;
  shape.name = name;
  if (is_template || has_initializers) return shape;
  if (name > begin && (Text(name - 1) == "::" || Text(name - 1) == "~")) return shape;
  if (!HasReturnType(begin, name)) return shape;
  for (size_t k = shape.lparen + 1; k < shape.rparen; ++k) {
    if (Text(k) == "=" || Text(k) == "{") return shape;  // default arguments
  }
  if (tokens_[begin].file != tokens_[end - 1].file) return shape;
  shape.eligible = true;
  return shape;
}

std::string Analyzer::Key(const Shape& shape) const {
  std::string key(Text(shape.name));
  key += '(';
  for (size_t k = shape.lparen + 1; k < shape.rparen; ++k) key += Text(k);
  key += ')';
  return key;
}

void Analyzer::PushCondLine(size_t i) {
  cond_lines_.push_back(i);
  cond_hash_.push_back(HashMix(CondHash(), Text(i)));
  cond_bytes_.push_back(CondBytes() + Text(i).size() + 1);
}

// Keeps the #if chains open at token `i` and the brace depth across them: each #elif/#else
// branch starts from the depth at its #if, and the depth after the first branch continues
// after #endif, so `#ifdef A void f() { #else void f(int) { #endif ... }` balances.
void Analyzer::Conditional(size_t i, int* depth, bool* expr_brace) {
  switch (tokens_[i].dir) {
    case DirKind::kIf: {
      CondFrame frame;
      frame.lines_begin = cond_lines_.size();
      frame.depth_at_if = *depth;
      frame.expr_at_if = *expr_brace;
      frames_.push_back(frame);
      PushCondLine(i);
      break;
    }
    case DirKind::kElse: {
      if (frames_.empty()) break;
      CondFrame& frame = frames_.back();
      if (frame.depth_after_first < 0) {
        frame.depth_after_first = *depth;
        frame.expr_after_first = *expr_brace;
      }
      *depth = frame.depth_at_if;
      *expr_brace = frame.expr_at_if;
      PushCondLine(i);
      break;
    }
    case DirKind::kEndif: {
      if (frames_.empty()) break;
      const CondFrame frame = frames_.back();
      frames_.pop_back();
      if (frame.depth_after_first >= 0) {
        *depth = frame.depth_after_first;
        *expr_brace = frame.expr_after_first;
      }
      cond_lines_.resize(frame.lines_begin);
      cond_hash_.resize(frame.lines_begin);
      cond_bytes_.resize(frame.lines_begin);
      break;
    }
    case DirKind::kOther:
      break;
  }
}

void Analyzer::NoteTypeName(size_t i, bool in_typedef) {
  const std::string_view s = Text(i);
  const size_t n = tokens_.size();
  if (OneOf(s, {"struct", "class", "union", "enum"})) {
    size_t k = i + 1;
    if (s == "enum" && k < n && (Text(k) == "class" || Text(k) == "struct")) ++k;
    if (k + 1 < n && IsName(k) && OneOf(Text(k + 1), {"{", ":", ";", "final"})) {
      type_first_.emplace(Text(k), i);
    }
  } else if (s == "using") {
    if (i + 2 < n && IsName(i + 1) && Text(i + 2) == "=") type_first_.emplace(Text(i + 1), i);
  } else if (in_typedef && i + 1 < n && IsName(i) && OneOf(Text(i + 1), {";", ",", ")", "["})) {
    type_first_.emplace(Text(i), i);
  }
}

void Analyzer::NoteDefinition(size_t begin, size_t end) {
  if (begin >= end) return;
  Definition def;
  def.shape = ParseHeader(begin, end);
  if (!def.shape.function_like) return;
  def.begin = begin;
  def.end = end;
  def.cond_depth = frames_.size();
  def.cond_hash = CondHash();
  if (def.shape.eligible && CondBytes() <= kMaxConditionBytes) {
    def.wrappable = true;
    for (const size_t line : cond_lines_) {
      def.cond_lines += Text(line);
      def.cond_lines += '\n';
    }
  }
  definitions_.push_back(std::move(def));
}

void Analyzer::NoteDeclaration(size_t begin, size_t end) {
  if (begin >= end) return;
  const Shape shape = ParseHeader(begin, end);
  if (!shape.eligible) return;
  std::string key = Key(shape);
  key += '|';  // conditional declarations only cover definitions under the same #if lines
  if (!frames_.empty()) key += std::to_string(CondHash());
  declarations_.push_back({begin, std::move(key)});
}

std::optional<std::string> Analyzer::Run() {
  int depth = 0;
  int parens = 0;           // ( and [ open in the current file-scope statement
  bool expr_brace = false;  // the open brace is inside a statement, e.g. `f({1, 2})`
  bool in_typedef = false;
  size_t statement = 0;  // first token of the current file-scope statement
  size_t outer_open = kNone;
  size_t stray_close = kNone;
  const size_t n = tokens_.size();
  for (size_t i = 0; i < n; ++i) {
    const SketchToken& t = tokens_[i];
    if (t.kind == TokKind::kDirective) {
      Conditional(i, &depth, &expr_brace);
      if (depth == 0 && parens == 0) statement = i + 1;
      continue;
    }
    const std::string_view s = Text(i);
    if (t.kind == TokKind::kIdent) {
      NoteTypeName(i, in_typedef && depth == 0);
      if (depth == 0 && s == "typedef") in_typedef = true;
      continue;
    }
    if (t.kind != TokKind::kPunct) continue;
    if ((s == "{" || s == "}") && !frames_.empty()) brace_in_conditional_ = true;
    if (depth > 0) {
      if (s == "{") {
        ++depth;
      } else if (s == "}" && --depth == 0) {
        if (expr_brace) {
          expr_brace = false;
        } else {
          statement = i + 1;
          parens = 0;
        }
      }
      continue;
    }
    if (s == "(" || s == "[") {
      ++parens;
    } else if (s == ")" || s == "]") {
      parens = std::max(0, parens - 1);
    } else if (s == ";") {
      NoteDeclaration(statement, i);
      statement = i + 1;
      parens = 0;
      in_typedef = false;
    } else if (s == "{") {
      outer_open = i;
      depth = 1;
      if (parens > 0) {
        expr_brace = true;
      } else {
        NoteDefinition(statement, i);
      }
    } else if (s == "}") {
      if (stray_close == kNone) stray_close = i;
      statement = i + 1;
      parens = 0;
    }
  }
  if (brace_in_conditional_) return std::nullopt;  // the compiler knows which groups count
  if (stray_close != kNone) return Locate(stray_close, "'}' without a matching '{'");
  if (depth > 0 && outer_open != kNone) return Locate(outer_open, "'{' is never closed");
  return std::nullopt;
}

// True when a name in the definition's header (other than the function's and its
// parameters' names) is first declared as a type after the prototype block but before the
// definition: the prototype would not compile where the block is.
bool Analyzer::UsesTypeDeclaredBetween(const Definition& def, size_t after) const {
  if (type_first_.empty()) return false;
  std::vector<size_t> declarators;
  size_t last_name = kNone;
  int names = 0;
  int nesting = 0;
  for (size_t k = def.shape.lparen + 1; k <= def.shape.rparen; ++k) {
    const std::string_view s = Text(k);
    if (k == def.shape.rparen || (nesting == 0 && s == ",")) {
      if (names >= 2) declarators.push_back(last_name);
      names = 0;
    } else if (IsOpener(s)) {
      ++nesting;
    } else if (IsCloser(s)) {
      --nesting;
    } else if (nesting == 0 && tokens_[k].kind == TokKind::kIdent) {
      last_name = k;
      ++names;
    }
  }
  for (size_t k = def.begin; k < def.end; ++k) {
    if (k == def.shape.name || tokens_[k].kind != TokKind::kIdent) continue;
    const auto it = type_first_.find(Text(k));
    if (it == type_first_.end() || it->second <= after || it->second >= def.begin) continue;
    if (std::find(declarators.begin(), declarators.end(), k) == declarators.end()) return true;
  }
  return false;
}

std::optional<Analyzer::Insertion> Analyzer::BuildInsertion() const {
  if (definitions_.empty()) return std::nullopt;
  // The block goes before the first definition outside #if groups, so that it is seen
  // whatever the conditions; a sketch with every definition inside groups gets it before
  // the first one.
  size_t first = 0;
  for (size_t d = 0; d < definitions_.size(); ++d) {
    if (definitions_[d].cond_depth == 0) {
      first = d;
      break;
    }
  }
  const size_t at = definitions_[first].begin;
  std::unordered_set<std::string> declared;
  for (const Declaration& declaration : declarations_) {
    if (declaration.begin < at) declared.insert(declaration.key);
  }
  std::unordered_set<std::string> emitted;
  std::string block;
  std::string_view open_lines;
  size_t open_depth = 0;
  auto close_groups = [&block, &open_depth] {
    for (; open_depth > 0; --open_depth) block += "#endif\n";
  };
  for (size_t d = first; d < definitions_.size(); ++d) {
    const Definition& def = definitions_[d];
    if (!def.shape.eligible || !def.wrappable) continue;
    std::string key = Key(def.shape);
    key += '|';
    if (declared.count(key) != 0) continue;  // declared outside any #if
    if (def.cond_depth > 0) key += std::to_string(def.cond_hash);
    if (declared.count(key) != 0 || !emitted.insert(key).second) continue;
    if (UsesTypeDeclaredBetween(def, at)) continue;
    if (def.cond_lines != open_lines || def.cond_depth != open_depth) {
      close_groups();
      block += def.cond_lines;
      open_lines = def.cond_lines;
      open_depth = def.cond_depth;
    }
    const SketchToken& head = tokens_[def.begin];
    const SketchToken& tail = tokens_[def.end - 1];
    block += LineDirective(head.line, files_[head.file].name);
    block += texts_[head.file].substr(head.begin, tail.end - head.begin);
    block += ";\n";
  }
  close_groups();
  if (block.empty()) return std::nullopt;
  const SketchToken& resume = tokens_[at];
  block += LineDirective(resume.line, files_[resume.file].name);
  return Insertion{resume.file, resume.begin, std::move(block)};
}

}  // namespace

std::variant<std::string, std::string> PrepareSketch(const std::vector<SketchFile>& files) {
  using Result = std::variant<std::string, std::string>;
  if (files.empty()) return Result(std::in_place_index<kPrepareError>, "sketch has no .ino files");
  std::vector<std::string_view> texts;
  texts.reserve(files.size());
  size_t total = 0;
  for (const SketchFile& file : files) {
    std::string_view text = file.text;
    if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
    texts.push_back(text);
    total += text.size() + file.name.size() + 32;
  }
  std::vector<SketchToken> tokens;
  if (auto error = ScanSketch(files, texts, &tokens)) {
    return Result(std::in_place_index<kPrepareError>, std::move(*error));
  }
  Analyzer analyzer(files, texts, tokens);
  if (auto error = analyzer.Run()) {
    return Result(std::in_place_index<kPrepareError>, std::move(*error));
  }
  const std::optional<Analyzer::Insertion> insertion = analyzer.BuildInsertion();

  std::string out;
  out.reserve(total + (insertion ? insertion->block.size() + 1 : 0) + 32);
  out += "#include <Arduino.h>\n";
  for (size_t i = 0; i < files.size(); ++i) {
    out += LineDirective(1, files[i].name);
    const std::string_view text = texts[i];
    if (insertion && insertion->file == i) {
      out += text.substr(0, insertion->offset);
      EndLine(&out);
      out += insertion->block;
      out += text.substr(insertion->offset);
    } else {
      out += text;
    }
    EndLine(&out);
  }
  return Result(std::in_place_index<kPreparedSource>, std::move(out));
}

std::vector<std::string> OrderInoFiles(std::vector<std::string> names,
                                       const std::string& main_name) {
  const std::string suffix = "/" + main_name;
  auto is_main = [&](const std::string& name) {
    return name == main_name ||
           (name.size() > suffix.size() &&
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0);
  };
  std::vector<std::string> ordered;
  ordered.reserve(names.size());
  const auto main_it = std::find_if(names.begin(), names.end(), is_main);
  if (main_it != names.end()) {
    ordered.push_back(std::move(*main_it));
    names.erase(main_it);
  }
  // std::string compares through char_traits<char>, which orders bytes as unsigned char.
  std::sort(names.begin(), names.end());
  for (std::string& name : names) ordered.push_back(std::move(name));
  return ordered;
}

}  // namespace moco::arduino
