// The sketch's entry point on the host Arduino core: setup() once, then loop()
// for ever, as the Arduino cores' main() does. Firmware with its own main()
// (plain C on avr-libc, ported) replaces this one: it is weak.
#include "moco_core.h"
#include "runtime_internal.h"

void setup() __attribute__((weak));
void loop() __attribute__((weak));

__attribute__((weak)) int main() {
  moco::arduino::StartFirmware();
  if (setup == nullptr || loop == nullptr) {
    moco::arduino::Stop("the sketch defines no setup() or no loop()");
  }
  for (const auto& core : moco::arduino::AddedCores()) {
    if (core.setup != nullptr) core.setup();
  }
  setup();
  for (;;) {
    loop();
    for (const auto& core : moco::arduino::AddedCores()) {
      if (core.loop != nullptr) core.loop();
    }
    // The Arduino cores' main loop runs serialEvent() and yield() between loops.
    moco::arduino::Call();
  }
}
