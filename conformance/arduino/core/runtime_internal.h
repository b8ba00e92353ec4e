// What the host Arduino core's entry point needs of its runtime
// (conformance/arduino/core/runtime.cpp) beyond include/moco_core.h.
#ifndef MOCO_CONFORMANCE_ARDUINO_CORE_RUNTIME_INTERNAL_H_
#define MOCO_CONFORMANCE_ARDUINO_CORE_RUNTIME_INTERNAL_H_

#include <vector>

namespace moco::arduino {

// The cores a glue file added (AddCore), in order.
struct AddedCore {
  void (*setup)();
  void (*loop)();
};
std::vector<AddedCore>& AddedCores();

// Connects to the runner (link.h) if not yet done; a program started outside
// it says how to run it and exits 2.
void StartFirmware();

}  // namespace moco::arduino

#endif  // MOCO_CONFORMANCE_ARDUINO_CORE_RUNTIME_INTERNAL_H_
