// Teensy's IntervalTimer on the host core: a periodic interrupt every
// `microseconds` (fractions kept to the nanosecond), at its exact simulated times.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_INTERVALTIMER_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_INTERVALTIMER_H_

#include "moco_core.h"

class IntervalTimer {
 public:
  IntervalTimer() = default;
  ~IntervalTimer() { end(); }
  bool begin(void (*isr)(), unsigned int microseconds) {
    return Begin(isr, static_cast<double>(microseconds) * 1000.0);
  }
  bool begin(void (*isr)(), int microseconds) {
    return Begin(isr, static_cast<double>(microseconds) * 1000.0);
  }
  bool begin(void (*isr)(), unsigned long microseconds) {
    return Begin(isr, static_cast<double>(microseconds) * 1000.0);
  }
  bool begin(void (*isr)(), float microseconds) {
    return Begin(isr, static_cast<double>(microseconds) * 1000.0);
  }
  bool begin(void (*isr)(), double microseconds) {
    return Begin(isr, static_cast<double>(microseconds) * 1000.0);
  }
  void update(unsigned int microseconds) { Update(microseconds * 1000.0); }
  void update(float microseconds) { Update(microseconds * 1000.0); }
  void update(double microseconds) { Update(microseconds * 1000.0); }
  void end();
  void priority(int /*level*/) {}
  operator bool() const;

 private:
  bool Begin(void (*isr)(), double period_ns);
  void Update(double period_ns);
  int id_ = -1;
};

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_INTERVALTIMER_H_
