// The serial driver's line speeds (termios B* constants) by baud rate: the one
// table behind every place that sets or reads a line's speed (the emulator's
// PTYs, the tap's serial device, mococheck's serial: and pty: targets).
#ifndef MOCO_BASE_TERMIOS_SPEED_H_
#define MOCO_BASE_TERMIOS_SPEED_H_

#include <termios.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace moco::base {

// The B* constant for `baud`, or nullopt when the driver has none for it.
std::optional<speed_t> TermiosSpeed(uint32_t baud);
// The baud rate of a B* constant, or nullopt for B0 and unknown values.
std::optional<uint32_t> BaudOfTermiosSpeed(speed_t speed);
// What to tell a user who asked for `baud`: that the rate cannot be set, and
// the rates to choose from instead; `usual`, when given, follows the list
// (the caller's devices' rates: base knows no protocol).
std::string NonStandardBaudHint(uint32_t baud, std::string_view usual = {});

}  // namespace moco::base

#endif  // MOCO_BASE_TERMIOS_SPEED_H_
