// Arduino's String on the host core (include/WString.h).
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

#include <string>

#include "WString.h"

namespace {

std::string Digits(unsigned long long value, unsigned base, bool negative) {
  if (base < 2 || base > 36) base = 10;
  std::string out;
  do {
    const unsigned d = static_cast<unsigned>(value % base);
    out.insert(out.begin(), static_cast<char>(d < 10 ? '0' + d : 'a' + d - 10));
    value /= base;
  } while (value != 0);
  if (negative) out.insert(out.begin(), '-');
  return out;
}

std::string Signed(long long value, unsigned base) {
  if (base == 10 && value < 0)
    return Digits(0ull - static_cast<unsigned long long>(value), 10, true);
  return Digits(static_cast<unsigned long long>(value), base, false);
}

std::string Fixed(double value, unsigned decimals) {
  char buffer[64];
  snprintf(buffer, sizeof(buffer), "%.*f", static_cast<int>(decimals > 20 ? 20 : decimals), value);
  return buffer;
}

}  // namespace

String::String(unsigned char value, unsigned char base) : s_(Digits(value, base, false)) {}
String::String(int value, unsigned char base) : s_(Signed(value, base)) {}
String::String(unsigned int value, unsigned char base) : s_(Digits(value, base, false)) {}
String::String(long value, unsigned char base) : s_(Signed(value, base)) {}
String::String(unsigned long value, unsigned char base) : s_(Digits(value, base, false)) {}
String::String(long long value, unsigned char base) : s_(Signed(value, base)) {}
String::String(unsigned long long value, unsigned char base) : s_(Digits(value, base, false)) {}
String::String(float value, unsigned char decimals) : s_(Fixed(value, decimals)) {}
String::String(double value, unsigned char decimals) : s_(Fixed(value, decimals)) {}

bool String::equalsIgnoreCase(const String& other) const {
  if (s_.size() != other.s_.size()) return false;
  for (size_t i = 0; i < s_.size(); ++i) {
    if (tolower(static_cast<unsigned char>(s_[i])) !=
        tolower(static_cast<unsigned char>(other.s_[i])))
      return false;
  }
  return true;
}

bool String::startsWith(const String& prefix, unsigned int offset) const {
  return offset <= s_.size() && s_.compare(offset, prefix.s_.size(), prefix.s_) == 0;
}

bool String::endsWith(const String& suffix) const {
  return suffix.s_.size() <= s_.size() &&
         s_.compare(s_.size() - suffix.s_.size(), suffix.s_.size(), suffix.s_) == 0;
}

char& String::operator[](unsigned int index) {
  if (index >= s_.size()) {
    dummy_ = '\0';
    return dummy_;
  }
  return s_[index];
}

void String::getBytes(unsigned char* buffer, unsigned int size, unsigned int index) const {
  if (buffer == nullptr || size == 0) return;
  if (index >= s_.size()) {
    buffer[0] = 0;
    return;
  }
  const size_t n = std::min<size_t>(size - 1, s_.size() - index);
  s_.copy(reinterpret_cast<char*>(buffer), n, index);
  buffer[n] = 0;
}

int String::indexOf(char c, unsigned int from) const {
  const size_t at = s_.find(c, from);
  return at == std::string::npos ? -1 : static_cast<int>(at);
}
int String::indexOf(const String& text, unsigned int from) const {
  const size_t at = s_.find(text.s_, from);
  return at == std::string::npos ? -1 : static_cast<int>(at);
}
int String::lastIndexOf(char c) const {
  const size_t at = s_.rfind(c);
  return at == std::string::npos ? -1 : static_cast<int>(at);
}
int String::lastIndexOf(const String& text) const {
  const size_t at = s_.rfind(text.s_);
  return at == std::string::npos ? -1 : static_cast<int>(at);
}

String String::substring(unsigned int from, unsigned int to) const {
  if (from > to) std::swap(from, to);
  if (from >= s_.size()) return String();
  to = std::min<unsigned int>(to, length());
  return String(s_.substr(from, to - from).c_str());
}

void String::replace(char find, char with) {
  for (char& c : s_)
    if (c == find) c = with;
}

void String::replace(const String& find, const String& with) {
  if (find.s_.empty()) return;
  for (size_t at = s_.find(find.s_); at != std::string::npos;
       at = s_.find(find.s_, at + with.s_.size())) {
    s_.replace(at, find.s_.size(), with.s_);
  }
}

void String::remove(unsigned int index, unsigned int count) {
  if (index < s_.size()) s_.erase(index, count);
}

void String::toLowerCase() {
  for (char& c : s_) c = static_cast<char>(tolower(static_cast<unsigned char>(c)));
}
void String::toUpperCase() {
  for (char& c : s_) c = static_cast<char>(toupper(static_cast<unsigned char>(c)));
}

void String::trim() {
  const size_t first = s_.find_first_not_of(" \t\r\n\f\v");
  if (first == std::string::npos) {
    s_.clear();
    return;
  }
  const size_t last = s_.find_last_not_of(" \t\r\n\f\v");
  s_ = s_.substr(first, last - first + 1);
}

long String::toInt() const { return atol(s_.c_str()); }
float String::toFloat() const { return static_cast<float>(atof(s_.c_str())); }
double String::toDouble() const { return atof(s_.c_str()); }
