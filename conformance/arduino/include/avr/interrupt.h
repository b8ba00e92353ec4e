// cli()/sei() on the host core: interrupts off and on (moco_core.h). ISR()
// vectors are an AVR's own and are not modelled: a ported firmware starts its
// interrupts through a timer API of the core (TimerOne.h) instead.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_INTERRUPT_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_INTERRUPT_H_

#include "moco_core.h"

#define cli() moco::arduino::InterruptsOff()
#define sei() moco::arduino::InterruptsOn()

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_INTERRUPT_H_
