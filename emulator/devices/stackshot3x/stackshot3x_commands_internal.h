// What the StackShot 3X command handler files share (stackshot3x_commands.cpp,
// stackshot3x_config_commands.cpp): reading a command's payload and checking a
// value's range. Internal to the StackShot 3X model.
#ifndef MOCO_EMULATOR_DEVICES_STACKSHOT3X_STACKSHOT3X_COMMANDS_INTERNAL_H_
#define MOCO_EMULATOR_DEVICES_STACKSHOT3X_STACKSHOT3X_COMMANDS_INTERNAL_H_

#include <variant>

#include "wire/stackshot.h"

namespace moco::devices::stackshot3x_commands {

// The payload of `c` as a T, or nullptr when it is another.
template <typename T>
const T* As(const stackshot::HostCommand& c) {
  return std::get_if<T>(&c.payload);
}

inline bool InRange(float v, float lo, float hi) { return v >= lo && v <= hi; }

}  // namespace moco::devices::stackshot3x_commands

#endif  // MOCO_EMULATOR_DEVICES_STACKSHOT3X_STACKSHOT3X_COMMANDS_INTERNAL_H_
