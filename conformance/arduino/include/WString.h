// Arduino's String on the host core, and the flash-string marker F() gives.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_WSTRING_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_WSTRING_H_

#include <stddef.h>

#include <string>

class __FlashStringHelper;
#define F(string_literal) (reinterpret_cast<const __FlashStringHelper*>(string_literal))

class String {
 public:
  String(const char* text = "") : s_(text == nullptr ? "" : text) {}
  String(const char* text, unsigned int length) : s_(text, length) {}
  String(const __FlashStringHelper* text) : String(reinterpret_cast<const char*>(text)) {}
  String(const String&) = default;
  String(String&&) = default;
  explicit String(char c) : s_(1, c) {}
  explicit String(unsigned char value, unsigned char base = 10);
  explicit String(int value, unsigned char base = 10);
  explicit String(unsigned int value, unsigned char base = 10);
  explicit String(long value, unsigned char base = 10);
  explicit String(unsigned long value, unsigned char base = 10);
  explicit String(long long value, unsigned char base = 10);
  explicit String(unsigned long long value, unsigned char base = 10);
  explicit String(float value, unsigned char decimals = 2);
  explicit String(double value, unsigned char decimals = 2);
  String& operator=(const String&) = default;
  String& operator=(String&&) = default;
  String& operator=(const char* text) {
    s_ = text == nullptr ? "" : text;
    return *this;
  }

  unsigned char reserve(unsigned int size) {
    s_.reserve(size);
    return 1;
  }
  unsigned int length() const { return static_cast<unsigned int>(s_.size()); }
  bool isEmpty() const { return s_.empty(); }
  const char* c_str() const { return s_.c_str(); }
  char* begin() { return s_.data(); }
  char* end() { return s_.data() + s_.size(); }

  unsigned char concat(const String& other) {
    s_ += other.s_;
    return 1;
  }
  unsigned char concat(const char* text) {
    if (text != nullptr) s_ += text;
    return 1;
  }
  unsigned char concat(char c) {
    s_ += c;
    return 1;
  }
  template <typename T>
  unsigned char concat(T value) {
    return concat(String(value));
  }
  template <typename T>
  String& operator+=(const T& value) {
    concat(value);
    return *this;
  }

  int compareTo(const String& other) const { return s_.compare(other.s_); }
  bool equals(const String& other) const { return s_ == other.s_; }
  bool equals(const char* text) const { return s_ == (text == nullptr ? "" : text); }
  bool equalsIgnoreCase(const String& other) const;
  bool operator==(const String& other) const { return equals(other); }
  bool operator==(const char* text) const { return equals(text); }
  bool operator!=(const String& other) const { return !equals(other); }
  bool operator!=(const char* text) const { return !equals(text); }
  bool operator<(const String& other) const { return s_ < other.s_; }
  bool operator>(const String& other) const { return s_ > other.s_; }
  bool startsWith(const String& prefix) const { return s_.rfind(prefix.s_, 0) == 0; }
  bool startsWith(const String& prefix, unsigned int offset) const;
  bool endsWith(const String& suffix) const;

  char charAt(unsigned int index) const { return index < s_.size() ? s_[index] : '\0'; }
  void setCharAt(unsigned int index, char c) {
    if (index < s_.size()) s_[index] = c;
  }
  char operator[](unsigned int index) const { return charAt(index); }
  char& operator[](unsigned int index);
  void getBytes(unsigned char* buffer, unsigned int size, unsigned int index = 0) const;
  void toCharArray(char* buffer, unsigned int size, unsigned int index = 0) const {
    getBytes(reinterpret_cast<unsigned char*>(buffer), size, index);
  }

  int indexOf(char c, unsigned int from = 0) const;
  int indexOf(const String& text, unsigned int from = 0) const;
  int lastIndexOf(char c) const;
  int lastIndexOf(const String& text) const;
  String substring(unsigned int from) const { return substring(from, length()); }
  String substring(unsigned int from, unsigned int to) const;

  void replace(char find, char with);
  void replace(const String& find, const String& with);
  void remove(unsigned int index) { remove(index, length()); }
  void remove(unsigned int index, unsigned int count);
  void toLowerCase();
  void toUpperCase();
  void trim();

  long toInt() const;
  float toFloat() const;
  double toDouble() const;

 private:
  std::string s_;
  char dummy_ = '\0';
};

inline String operator+(const String& a, const String& b) {
  String s(a);
  s += b;
  return s;
}
inline String operator+(const String& a, const char* b) {
  String s(a);
  s += b;
  return s;
}
inline String operator+(const char* a, const String& b) {
  String s(a);
  s += b;
  return s;
}
template <typename T>
String operator+(const String& a, T b) {
  String s(a);
  s += b;
  return s;
}

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_WSTRING_H_
