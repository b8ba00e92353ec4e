// The lexer of sketch preprocessing: comments, literals, directives and `#if 0` groups.
#include "conformance/arduino/tools/sketch_scan.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace moco::arduino {
namespace {

bool IsIdentStart(unsigned char c) {
  // Bytes >= 0x80 are UTF-8 identifier characters as far as GCC is concerned.
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' || c == '$' || c >= 0x80;
}
bool IsDigit(unsigned char c) { return c >= '0' && c <= '9'; }
bool IsIdentChar(unsigned char c) { return IsIdentStart(c) || IsDigit(c); }
bool IsHorizontalSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

// Splits the sketch into tokens, dropping comments and the bodies of `#if 0` groups and
// turning each preprocessor directive into one kDirective token.
class Lexer {
 public:
  explicit Lexer(std::vector<SketchToken>* tokens) : tokens_(tokens) {}

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

  std::vector<SketchToken>* tokens_;
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
  SketchToken token;
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

}  // namespace

std::string Located(std::string_view file, uint32_t line, std::string_view what) {
  std::string message(file);
  message += ':';
  message += std::to_string(line);
  message += ": ";
  message += what;
  return message;
}

std::optional<std::string> ScanSketch(const std::vector<SketchFile>& files,
                                      const std::vector<std::string_view>& texts,
                                      std::vector<SketchToken>* tokens) {
  Lexer lexer(tokens);
  for (size_t i = 0; i < files.size(); ++i) {
    if (auto error = lexer.Lex(static_cast<uint32_t>(i), texts[i], files[i].name)) return error;
  }
  return std::nullopt;
}

}  // namespace moco::arduino
