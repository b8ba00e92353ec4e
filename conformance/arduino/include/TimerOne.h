// The generic periodic timer on the host core, with the interface of the
// TimerOne library that AVR and other sketches use: Timer1.initialize(us),
// attachInterrupt(isr), start(), stop(); the interrupt comes at its exact
// simulated times.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_TIMERONE_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_TIMERONE_H_

#include "moco_core.h"

class TimerOne {
 public:
  // The period in microseconds (default 1 s); the timer runs from here.
  void initialize(unsigned long microseconds = 1000000);
  void setPeriod(unsigned long microseconds);
  // Nanosecond periods, for a firmware whose own timer runs at a fraction
  // of a microsecond (F_CPU / OCR).
  void setPeriodNs(int64_t period_ns);
  void attachInterrupt(void (*isr)());
  void attachInterrupt(void (*isr)(), unsigned long microseconds);
  void detachInterrupt();
  void start();
  void stop();
  void restart() { start(); }
  void resume();
  unsigned long read();

 private:
  int Id();
  int id_ = -1;
  int64_t period_ns_ = 1000000000;
};
extern TimerOne Timer1;

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_TIMERONE_H_
