// Arduino sketch preprocessing (Arduino CLI "Sketch build process"): a small C++ lexer and a
// file-scope walk find the function definitions that need prototypes, without running a
// compiler or ctags.
#include "conformance/arduino/tools/sketch_prep.h"

#include <algorithm>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string_view>
#include <unordered_map>
#include <unordered_set>
#include <utility>

namespace moco::arduino {
namespace {

constexpr size_t kNone = static_cast<size_t>(-1);
// Longest text of #if/#elif/#else lines repeated around one prototype; a definition nested
// deeper than this gets no prototype, which keeps the output linear in the input.
constexpr size_t kMaxConditionBytes = 512;

enum class TokKind : uint8_t { kIdent, kNumber, kLiteral, kPunct, kDirective };
// What a directive does to conditional compilation.
enum class DirKind : uint8_t { kOther, kIf, kElse, kEndif };

struct Token {
  size_t begin = 0;  // byte offsets into the file's text
  size_t end = 0;
  uint32_t file = 0;
  uint32_t line = 0;  // 1-based line of `begin`
  TokKind kind = TokKind::kPunct;
  DirKind dir = DirKind::kOther;
};

bool IsIdentStart(unsigned char c) {
  // Bytes >= 0x80 are UTF-8 identifier characters as far as GCC is concerned.
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == '$' || c >= 0x80;
}
bool IsDigit(unsigned char c) { return c >= '0' && c <= '9'; }
bool IsIdentChar(unsigned char c) { return IsIdentStart(c) || IsDigit(c); }
bool IsHorizontalSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

bool OneOf(std::string_view word, std::initializer_list<std::string_view> words) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

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

std::string Located(std::string_view file, uint32_t line, std::string_view what) {
  std::string message(file);
  message += ':';
  message += std::to_string(line);
  message += ": ";
  message += what;
  return message;
}

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

// Splits the sketch into tokens, dropping comments and the bodies of `#if 0` groups and
// turning each preprocessor directive into one kDirective token.
class Lexer {
 public:
  explicit Lexer(std::vector<Token>* tokens) : tokens_(tokens) {}

  // Appends the tokens of one file; returns "<name>:<line>: <what>" on malformed input.
  // The state of an open `#if 0` group carries over to the next file, as in the
  // concatenated source.
  std::optional<std::string> Lex(uint32_t file, std::string_view text, std::string_view name);

 private:
  char Peek(size_t ahead) const { return pos_ + ahead < text_.size() ? text_[pos_ + ahead] : '\0'; }
  // Length of a backslash-newline at `at`, 0 if there is none.
  size_t SpliceLength(size_t at) const;
  void Fail(uint32_t line, std::string_view what) { error_ = Located(name_, line, what); }
  bool SkipBlockComment();
  void SkipLineComment();
  // `pos_` at the opening quote. A lenient literal ends quietly at the end of the line, as
  // text in skipped groups and directives may hold lone apostrophes.
  bool SkipQuoted(char quote, bool lenient);
  bool SkipRawString(bool lenient);  // `pos_` at the '"' after the R prefix
  bool LexDirective();
  void Emit(TokKind kind, size_t begin, uint32_t line, DirKind dir = DirKind::kOther);
  bool Skipping() const { return skip_nest_ >= 0; }

  std::vector<Token>* tokens_;
  std::string_view text_;
  std::string_view name_;
  uint32_t file_ = 0;
  size_t pos_ = 0;
  uint32_t line_ = 1;
  // -1 outside a skipped `#if 0` group, else the number of #if nested inside it.
  int skip_nest_ = -1;
  std::string error_;
};

size_t Lexer::SpliceLength(size_t at) const {
  if (at >= text_.size() || text_[at] != '\\') return 0;
  if (at + 1 < text_.size() && text_[at + 1] == '\n') return 2;
  if (at + 2 < text_.size() && text_[at + 1] == '\r' && text_[at + 2] == '\n') return 3;
  return 0;
}

bool Lexer::SkipBlockComment() {
  const size_t close = text_.find("*/", pos_ + 2);
  if (close == std::string_view::npos) {
    Fail(line_, "unterminated /* comment");
    return false;
  }
  line_ +=
      static_cast<uint32_t>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                       text_.begin() + static_cast<std::ptrdiff_t>(close), '\n'));
  pos_ = close + 2;
  return true;
}

void Lexer::SkipLineComment() {
  const size_t start = pos_;
  while (true) {
    const size_t newline = text_.find('\n', pos_);
    if (newline == std::string_view::npos) {
      pos_ = text_.size();
      return;
    }
    size_t k = newline;
    if (k > start && text_[k - 1] == '\r') --k;
    if (k > start && text_[k - 1] == '\\') {  // a backslash continues the comment
      ++line_;
      pos_ = newline + 1;
      continue;
    }
    pos_ = newline;
    return;
  }
}

bool Lexer::SkipQuoted(char quote, bool lenient) {
  const uint32_t start_line = line_;
  ++pos_;
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == quote) {
      ++pos_;
      return true;
    }
    if (c == '\\') {
      if (const size_t splice = SpliceLength(pos_)) {
        pos_ += splice;
        ++line_;
      } else {
        pos_ = std::min(pos_ + 2, text_.size());
      }
      continue;
    }
    if (c == '\n') break;
    ++pos_;
  }
  if (lenient) return true;
  Fail(start_line,
       quote == '"' ? "missing terminating \" character" : "missing terminating ' character");
  return false;
}

bool Lexer::SkipRawString(bool lenient) {
  const uint32_t start_line = line_;
  const size_t open = pos_ + 1;
  size_t paren = open;
  while (paren < text_.size() && paren - open <= 16) {
    const char c = text_[paren];
    if (c == '(' || c == ')' || c == '\\' || c == '"' || c == ' ' || c == '\t' || c == '\v' ||
        c == '\f' || c == '\n' || c == '\r') {
      break;
    }
    ++paren;
  }
  if (paren >= text_.size() || text_[paren] != '(' || paren - open > 16) {
    if (lenient) return SkipQuoted('"', true);
    Fail(start_line, "invalid raw string delimiter");
    return false;
  }
  std::string closing = ")";
  closing += text_.substr(open, paren - open);
  closing += '"';
  const size_t close = text_.find(closing, paren + 1);
  if (close == std::string_view::npos) {
    if (lenient) return SkipQuoted('"', true);
    Fail(start_line, "unterminated raw string");
    return false;
  }
  const size_t end = close + closing.size();
  line_ +=
      static_cast<uint32_t>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                       text_.begin() + static_cast<std::ptrdiff_t>(end), '\n'));
  pos_ = end;
  return true;
}

bool Lexer::LexDirective() {
  const size_t begin = pos_;
  const uint32_t line = line_;
  ++pos_;
  while (pos_ < text_.size()) {
    if (IsHorizontalSpace(text_[pos_])) {
      ++pos_;
    } else if (const size_t splice = SpliceLength(pos_)) {
      pos_ += splice;
      ++line_;
    } else if (text_[pos_] == '/' && Peek(1) == '*') {
      if (!SkipBlockComment()) return false;
    } else {
      break;
    }
  }
  const size_t name_begin = pos_;
  while (pos_ < text_.size() && IsIdentChar(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  const std::string_view name = text_.substr(name_begin, pos_ - name_begin);
  DirKind kind = DirKind::kOther;
  if (OneOf(name, {"if", "ifdef", "ifndef"})) {
    kind = DirKind::kIf;
  } else if (OneOf(name, {"elif", "else", "elifdef", "elifndef"})) {
    kind = DirKind::kElse;
  } else if (name == "endif") {
    kind = DirKind::kEndif;
  }
  // The condition without blanks or comments, enough to recognise `#if 0`.
  const bool has_condition = name == "if" || name == "elif";
  std::string condition;
  while (pos_ < text_.size() && text_[pos_] != '\n') {
    const char c = text_[pos_];
    if (const size_t splice = SpliceLength(pos_)) {
      pos_ += splice;
      ++line_;
    } else if (c == '/' && Peek(1) == '*') {
      if (!SkipBlockComment()) return false;
    } else if (c == '/' && Peek(1) == '/') {
      SkipLineComment();
    } else if (c == '"' || c == '\'') {
      SkipQuoted(c, /*lenient=*/true);
      condition += c;
    } else {
      if (has_condition && !IsHorizontalSpace(c) && condition.size() < 8) condition += c;
      ++pos_;
    }
  }
  const bool never_true = has_condition && (condition == "0" || condition == "false");
  if (Skipping()) {
    if (kind == DirKind::kIf) {
      ++skip_nest_;
    } else if (kind == DirKind::kEndif) {
      if (skip_nest_ == 0) {
        skip_nest_ = -1;
        Emit(TokKind::kDirective, begin, line, kind);
      } else {
        --skip_nest_;
      }
    } else if (kind == DirKind::kElse && skip_nest_ == 0) {
      skip_nest_ = -1;
      Emit(TokKind::kDirective, begin, line, kind);
      if (never_true) skip_nest_ = 0;
    }
    return true;
  }
  Emit(TokKind::kDirective, begin, line, kind);
  if (never_true && kind != DirKind::kOther) skip_nest_ = 0;
  return true;
}

void Lexer::Emit(TokKind kind, size_t begin, uint32_t line, DirKind dir) {
  if (Skipping() && kind != TokKind::kDirective) return;
  Token token;
  token.begin = begin;
  token.end = pos_;
  token.file = file_;
  token.line = line;
  token.kind = kind;
  token.dir = dir;
  tokens_->push_back(token);
}

std::optional<std::string> Lexer::Lex(uint32_t file, std::string_view text, std::string_view name) {
  text_ = text;
  name_ = name;
  file_ = file;
  pos_ = 0;
  line_ = 1;
  bool at_line_start = true;  // only blanks and comments so far on this line
  const size_t n = text_.size();
  while (pos_ < n) {
    const auto c = static_cast<unsigned char>(text_[pos_]);
    if (c == '\n') {
      ++line_;
      ++pos_;
      at_line_start = true;
      continue;
    }
    if (IsHorizontalSpace(static_cast<char>(c))) {
      ++pos_;
      continue;
    }
    if (const size_t splice = SpliceLength(pos_)) {
      pos_ += splice;
      ++line_;
      continue;
    }
    if (c == '/' && Peek(1) == '/') {
      SkipLineComment();
      continue;
    }
    if (c == '/' && Peek(1) == '*') {
      if (!SkipBlockComment()) return error_;
      continue;
    }
    if (c == '#' && at_line_start) {
      if (!LexDirective()) return error_;
      continue;
    }
    at_line_start = false;
    const size_t begin = pos_;
    const uint32_t line = line_;
    if (IsIdentStart(c)) {
      while (pos_ < n && IsIdentChar(static_cast<unsigned char>(text_[pos_]))) ++pos_;
      const std::string_view word = text_.substr(begin, pos_ - begin);
      const char next = Peek(0);
      if (next == '"' && OneOf(word, {"R", "LR", "uR", "UR", "u8R"})) {
        if (!SkipRawString(Skipping())) return error_;
        Emit(TokKind::kLiteral, begin, line);
      } else if ((next == '"' || next == '\'') && OneOf(word, {"L", "u", "U", "u8"})) {
        if (!SkipQuoted(next, Skipping())) return error_;
        Emit(TokKind::kLiteral, begin, line);
      } else {
        Emit(TokKind::kIdent, begin, line);
      }
    } else if (IsDigit(c) || (c == '.' && IsDigit(static_cast<unsigned char>(Peek(1))))) {
      ++pos_;
      while (pos_ < n) {
        const auto d = static_cast<unsigned char>(text_[pos_]);
        const char before = text_[pos_ - 1];
        if ((d == '+' || d == '-') &&
            (before == 'e' || before == 'E' || before == 'p' || before == 'P')) {
          ++pos_;
        } else if (IsIdentChar(d) || d == '.') {
          ++pos_;
        } else if (d == '\'' && IsIdentChar(static_cast<unsigned char>(Peek(1)))) {
          pos_ += 2;  // digit separator
        } else {
          break;
        }
      }
      Emit(TokKind::kNumber, begin, line);
    } else if (c == '"' || c == '\'') {
      if (!SkipQuoted(static_cast<char>(c), Skipping())) return error_;
      Emit(TokKind::kLiteral, begin, line);
    } else {
      static constexpr std::string_view kLong[] = {
          "<<=", ">>=", "...", "->*", "::", "->", "==", "!=", "<=", ">=", "&&", "||", "<<",
          ">>",  "++",  "--",  "+=",  "-=", "*=", "/=", "%=", "&=", "|=", "^=", ".*", "##"};
      size_t length = 1;
      for (const std::string_view op : kLong) {
        if (text_.substr(pos_, op.size()) == op) {
          length = op.size();
          break;
        }
      }
      pos_ += length;
      Emit(TokKind::kPunct, begin, line);
    }
  }
  return std::nullopt;
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
           const std::vector<Token>& tokens)
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
    const Token& t = tokens_[i];
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
  const std::vector<Token>& tokens_;
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
    const Token& t = tokens_[j];
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
    const Token& t = tokens_[i];
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
    const Token& head = tokens_[def.begin];
    const Token& tail = tokens_[def.end - 1];
    block += LineDirective(head.line, files_[head.file].name);
    block += texts_[head.file].substr(head.begin, tail.end - head.begin);
    block += ";\n";
  }
  close_groups();
  if (block.empty()) return std::nullopt;
  const Token& resume = tokens_[at];
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
  std::vector<Token> tokens;
  Lexer lexer(&tokens);
  for (size_t i = 0; i < files.size(); ++i) {
    if (auto error = lexer.Lex(static_cast<uint32_t>(i), texts[i], files[i].name)) {
      return Result(std::in_place_index<kPrepareError>, std::move(*error));
    }
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
