// An AVR's idle sleep on the host core: sleep_cpu() waits for the next timer
// interrupt or serial byte; the modes are accepted and all idle alike.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_SLEEP_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_SLEEP_H_

#include "moco_core.h"

#define SLEEP_MODE_IDLE 0
#define set_sleep_mode(mode) ((void)(mode))
#define sleep_enable() ((void)0)
#define sleep_disable() ((void)0)
// Interrupts on, as sleep is entered with sei() just before it on an AVR.
#define sleep_cpu() (moco::arduino::InterruptsOn(), moco::arduino::WaitForEvent())
#define sleep_mode() sleep_cpu()

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_AVR_SLEEP_H_
