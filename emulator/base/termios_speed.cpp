#include "base/termios_speed.h"

#include <array>

namespace moco::base {
namespace {

struct Rate {
  uint32_t baud;
  speed_t speed;
};

// Every rate Linux's termios names (termios-baud.h), slowest first.
constexpr std::array<Rate, 30> kRates = {{
    {50, B50},           {75, B75},           {110, B110},         {134, B134},
    {150, B150},         {200, B200},         {300, B300},         {600, B600},
    {1200, B1200},       {1800, B1800},       {2400, B2400},       {4800, B4800},
    {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},
    {115200, B115200},   {230400, B230400},   {460800, B460800},   {500000, B500000},
    {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
    {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000},
    {3500000, B3500000}, {4000000, B4000000},
}};

}  // namespace

std::optional<speed_t> TermiosSpeed(uint32_t baud) {
  for (const Rate& r : kRates) {
    if (r.baud == baud) return r.speed;
  }
  return std::nullopt;
}

std::optional<uint32_t> BaudOfTermiosSpeed(speed_t speed) {
  for (const Rate& r : kRates) {
    if (r.speed == speed) return r.baud;
  }
  return std::nullopt;
}

std::string NonStandardBaudHint(uint32_t baud, std::string_view usual) {
  std::string list;
  for (const Rate& r : kRates) {
    if (r.baud < 1200) continue;  // named, but no motion controller runs that slow
    list += (list.empty() ? "" : ", ") + std::to_string(r.baud);
  }
  if (!usual.empty()) list += "; " + std::string(usual);
  return "baud rate " + std::to_string(baud) +
         " is not one the serial driver can set; use a standard rate (" + list + ")";
}

}  // namespace moco::base
