// Teensy's elapsedMillis / elapsedMicros on the host core's clock.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_ELAPSEDMILLIS_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_ELAPSEDMILLIS_H_

unsigned long millis();
unsigned long micros();

template <unsigned long (*Clock)()>
class ElapsedClock {
 public:
  ElapsedClock() : start_(Clock()) {}
  explicit ElapsedClock(unsigned long value) : start_(Clock() - value) {}
  operator unsigned long() const { return Clock() - start_; }
  ElapsedClock& operator=(unsigned long value) {
    start_ = Clock() - value;
    return *this;
  }
  ElapsedClock& operator-=(unsigned long value) {
    start_ += value;
    return *this;
  }
  ElapsedClock& operator+=(unsigned long value) {
    start_ -= value;
    return *this;
  }

 private:
  unsigned long start_;
};
using elapsedMillis = ElapsedClock<millis>;
using elapsedMicros = ElapsedClock<micros>;

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_ELAPSEDMILLIS_H_
