// ArduinoCore-API's byte ring buffer (RingBufferN<N>, RingBuffer), which the
// cores built on that API (mbed: GIGA, Portenta, Nano 33 BLE) give a sketch
// through Arduino.h: store_char() drops a byte when full, read_char() and
// peek() give -1 when empty. No simulated time passes in it.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_RINGBUFFER_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_RINGBUFFER_H_

#include <stdint.h>

template <int N>
class RingBufferN {
 public:
  void store_char(uint8_t c) {
    if (count_ >= N) return;
    data_[head_] = c;
    head_ = Next(head_);
    ++count_;
  }
  void clear() { head_ = tail_ = count_ = 0; }
  int read_char() {
    if (count_ == 0) return -1;
    const uint8_t c = data_[tail_];
    tail_ = Next(tail_);
    --count_;
    return c;
  }
  int peek() { return count_ == 0 ? -1 : data_[tail_]; }
  int available() { return count_; }
  int availableForStore() { return N - count_; }
  bool isFull() { return count_ == N; }

 private:
  static int Next(int i) { return i + 1 == N ? 0 : i + 1; }
  uint8_t data_[N] = {};
  volatile int head_ = 0;
  volatile int tail_ = 0;
  volatile int count_ = 0;
};

typedef RingBufferN<64> RingBuffer;

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_RINGBUFFER_H_
