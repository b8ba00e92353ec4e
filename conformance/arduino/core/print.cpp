// Arduino's Print and Stream on the host core (include/Print.h, Stream.h).
#include <stdarg.h>
#include <stdio.h>

#include <string>

#include "Arduino.h"

size_t Print::write(const uint8_t* buffer, size_t size) {
  size_t n = 0;
  for (size_t i = 0; i < size; ++i) {
    if (write(buffer[i]) == 0) break;
    ++n;
  }
  return n;
}

size_t Print::print(const __FlashStringHelper* text) {
  return print(reinterpret_cast<const char*>(text));
}
size_t Print::print(const String& text) { return write(text.c_str(), text.length()); }
size_t Print::print(const char* text) { return write(text); }
size_t Print::print(char c) { return write(static_cast<uint8_t>(c)); }
size_t Print::print(unsigned char value, int base) {
  return print(static_cast<unsigned long>(value), base);
}
size_t Print::print(int value, int base) { return print(static_cast<long long>(value), base); }
size_t Print::print(unsigned int value, int base) {
  return print(static_cast<unsigned long long>(value), base);
}
size_t Print::print(long value, int base) { return print(static_cast<long long>(value), base); }
size_t Print::print(unsigned long value, int base) {
  return print(static_cast<unsigned long long>(value), base);
}
size_t Print::print(long long value, int base) {
  if (base == 0) return write(static_cast<uint8_t>(value));
  if (base == 10 && value < 0) {
    return PrintNumber(0ull - static_cast<unsigned long long>(value), 10, true);
  }
  return PrintNumber(static_cast<unsigned long long>(value), base, false);
}
size_t Print::print(unsigned long long value, int base) {
  if (base == 0) return write(static_cast<uint8_t>(value));
  return PrintNumber(value, base, false);
}

size_t Print::PrintNumber(unsigned long long value, int base, bool negative) {
  if (base < 2) base = 10;
  char buffer[72];
  char* p = buffer + sizeof(buffer);
  *--p = '\0';
  do {
    const int digit = static_cast<int>(value % static_cast<unsigned>(base));
    *--p = static_cast<char>(digit < 10 ? '0' + digit : 'A' + digit - 10);
    value /= static_cast<unsigned>(base);
  } while (value != 0);
  if (negative) *--p = '-';
  return write(p);
}

size_t Print::print(double value, int digits) {
  if (isnan(value)) return print("nan");
  if (isinf(value)) return print("inf");
  if (value > 4294967040.0 || value < -4294967040.0) return print("ovf");
  char buffer[64];
  snprintf(buffer, sizeof(buffer), "%.*f", digits < 0 ? 0 : (digits > 20 ? 20 : digits), value);
  return print(buffer);
}

size_t Print::println() { return write("\r\n"); }

size_t Print::printf(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list copy;
  va_copy(copy, args);
  const int n = vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (n <= 0) {
    va_end(args);
    return 0;
  }
  std::string text(static_cast<size_t>(n) + 1, '\0');
  vsnprintf(text.data(), text.size(), format, args);
  va_end(args);
  return write(text.data(), static_cast<size_t>(n));
}

int Stream::TimedRead() {
  const unsigned long start = millis();
  do {
    const int c = read();
    if (c >= 0) return c;
  } while (millis() - start < timeout_ms_);
  return -1;
}

int Stream::TimedPeek() {
  const unsigned long start = millis();
  do {
    const int c = peek();
    if (c >= 0) return c;
  } while (millis() - start < timeout_ms_);
  return -1;
}

int Stream::PeekNextDigit(LookaheadMode lookahead, bool detect_decimal) {
  for (;;) {
    const int c = TimedPeek();
    if (c < 0 || c == '-' || (c >= '0' && c <= '9') || (detect_decimal && c == '.')) return c;
    if (lookahead == SKIP_NONE) return -1;
    if (lookahead == SKIP_WHITESPACE && !(c == ' ' || c == '\t' || c == '\r' || c == '\n'))
      return -1;
    read();
  }
}

bool Stream::find(const char* target) { return find(target, strlen(target)); }

bool Stream::find(const char* target, size_t length) {
  if (length == 0) return true;
  size_t matched = 0;
  for (;;) {
    const int c = TimedRead();
    if (c < 0) return false;
    if (c == static_cast<uint8_t>(target[matched])) {
      if (++matched == length) return true;
    } else {
      matched = c == static_cast<uint8_t>(target[0]) ? 1 : 0;
    }
  }
}

bool Stream::findUntil(const char* target, const char* terminator) {
  const size_t tl = strlen(target), el = terminator == nullptr ? 0 : strlen(terminator);
  size_t t = 0, e = 0;
  for (;;) {
    const int c = TimedRead();
    if (c < 0) return false;
    t = c == static_cast<uint8_t>(target[t]) ? t + 1 : (c == static_cast<uint8_t>(target[0]));
    if (t == tl) return true;
    if (el > 0) {
      e = c == static_cast<uint8_t>(terminator[e]) ? e + 1
                                                   : (c == static_cast<uint8_t>(terminator[0]));
      if (e == el) return false;
    }
  }
}

long Stream::parseInt(LookaheadMode lookahead, char ignore) {
  int c = PeekNextDigit(lookahead, false);
  if (c < 0) return 0;
  bool negative = false;
  long value = 0;
  do {
    if (c == ignore) {
    } else if (c == '-') {
      negative = true;
    } else if (c >= '0' && c <= '9') {
      value = value * 10 + c - '0';
    }
    read();
    c = TimedPeek();
  } while ((c >= '0' && c <= '9') || c == ignore);
  return negative ? -value : value;
}

float Stream::parseFloat(LookaheadMode lookahead, char ignore) {
  int c = PeekNextDigit(lookahead, true);
  if (c < 0) return 0;
  bool negative = false, fraction = false;
  double value = 0, scale = 1;
  do {
    if (c == ignore) {
    } else if (c == '-') {
      negative = true;
    } else if (c == '.') {
      fraction = true;
    } else if (c >= '0' && c <= '9') {
      value = value * 10 + c - '0';
      if (fraction) scale *= 0.1;
    }
    read();
    c = TimedPeek();
  } while ((c >= '0' && c <= '9') || (c == '.' && !fraction) || c == ignore);
  const double v = value * scale;
  return static_cast<float>(negative ? -v : v);
}

size_t Stream::readBytes(char* buffer, size_t length) {
  size_t n = 0;
  while (n < length) {
    const int c = TimedRead();
    if (c < 0) break;
    buffer[n++] = static_cast<char>(c);
  }
  return n;
}

size_t Stream::readBytesUntil(char terminator, char* buffer, size_t length) {
  size_t n = 0;
  while (n < length) {
    const int c = TimedRead();
    if (c < 0 || c == static_cast<uint8_t>(terminator)) break;
    buffer[n++] = static_cast<char>(c);
  }
  return n;
}

String Stream::readString() {
  String s;
  for (int c = TimedRead(); c >= 0; c = TimedRead()) s += static_cast<char>(c);
  return s;
}

String Stream::readStringUntil(char terminator) {
  String s;
  for (int c = TimedRead(); c >= 0 && c != static_cast<uint8_t>(terminator); c = TimedRead()) {
    s += static_cast<char>(c);
  }
  return s;
}
