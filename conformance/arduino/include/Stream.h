// Arduino's Stream on the host core: reads with a timeout in simulated time.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_STREAM_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_STREAM_H_

#include "Print.h"

enum LookaheadMode { SKIP_ALL, SKIP_NONE, SKIP_WHITESPACE };

class Stream : public Print {
 public:
  virtual int available() = 0;
  virtual int read() = 0;
  virtual int peek() = 0;

  void setTimeout(unsigned long timeout_ms) { timeout_ms_ = timeout_ms; }
  unsigned long getTimeout() const { return timeout_ms_; }
  bool find(const char* target);
  bool find(char target) { return find(&target, 1); }
  bool find(const char* target, size_t length);
  bool findUntil(const char* target, const char* terminator);
  long parseInt(LookaheadMode lookahead = SKIP_ALL, char ignore = '\x01');
  float parseFloat(LookaheadMode lookahead = SKIP_ALL, char ignore = '\x01');
  size_t readBytes(char* buffer, size_t length);
  size_t readBytes(uint8_t* buffer, size_t length) {
    return readBytes(reinterpret_cast<char*>(buffer), length);
  }
  size_t readBytesUntil(char terminator, char* buffer, size_t length);
  size_t readBytesUntil(char terminator, uint8_t* buffer, size_t length) {
    return readBytesUntil(terminator, reinterpret_cast<char*>(buffer), length);
  }
  String readString();
  String readStringUntil(char terminator);

 protected:
  // A byte within the timeout, or -1 (each try costs a clock read).
  int TimedRead();
  int TimedPeek();
  int PeekNextDigit(LookaheadMode lookahead, bool detect_decimal);
  unsigned long timeout_ms_ = 1000;
};

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_STREAM_H_
