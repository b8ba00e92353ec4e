// The StackShot command table (stackshot-protocol.txt section 2 tables,
// with the decisions for the commands the spec lists without a table): the
// data layout of each direction of each command, by id.
#include <algorithm>
#include <iterator>

#include "wire/stackshot.h"

namespace moco::stackshot {
namespace {

// ---------------------------------------------------------------------------
// The command table (section 2 tables, with the decisions for the commands
// the spec lists without a table).
// ---------------------------------------------------------------------------
constexpr Shape N = Shape::kNone;
constexpr Shape E = Shape::kEmpty;

// clang-format off
constexpr CommandInfo kCommands[] = {
  {0x1000, "CC_RAIL_MOVE",                   N, N, Shape::kRailMove, "", "2 CC_RAIL_MOVE"},
  {0x1001, "CC_RAIL_POSITION_TARGET",        Shape::kUnitsQuery, Shape::kUnitsF32, N, "position",
   "2 CC_RAIL_POSITION_TARGET; ERRATA 3.4 (response 5 bytes)"},
  {0x1002, "CC_RAIL_POSITION_CURRENT",       Shape::kUnitsQuery, Shape::kUnitsF32, N, "position",
   "2 CC_RAIL_POSITION_CURRENT; examples send no units byte"},
  {0x1003, "CC_RAIL_POSITION_ZERO",          N, N, E, "", "2 CC_RAIL_POSITION_ZERO"},
  {0x1004, "CC_RAIL_SHUTTER_FIRE",           N, N, Shape::kShutterFire, "", "2 CC_RAIL_SHUTTER_FIRE"},
  {0x1005, "CC_RAIL_STATUS",                 E, Shape::kRailStatus, N, "status", "2 CC_RAIL_STATUS"},
  // No table: StackShot_Stop (1.1.7) takes no parameters; write, no data.
  {0x1006, "CC_RAIL_STOP",                   N, N, E, "", "1.1.7 (no table)"},
  {0x1007, "CC_RAIL_MOVE_AT_SPEED",          N, N, Shape::kRailMoveAtSpeed, "", "2 CC_RAIL_MOVE_AT_SPEED"},
  {0x1008, "CC_RAIL_STACK",                  N, N, Shape::kRailStack, "", "2 CC_RAIL_STACK (48 bytes, 44 listed)"},
  // No table: read-only; the reply is taken to be a status bit field like
  // CC_RAIL_STATUS.
  {0x1009, "CC_RAIL_STACK_STATUS",           E, Shape::kRailStatus, N, "status", "1.2 enum only (decided)"},
  // No table: read-only; the reply is taken to be a u32 count of the stack
  // steps taken so far.
  {0x100A, "CC_RAIL_STACK_POSITION",         E, Shape::kU32, N, "step", "1.2 enum only (decided)"},
  // No table: like CC_RAIL_STOP, with a soft ramp; write, no data.
  {0x100B, "CC_RAIL_STOP_RAMP",              N, N, E, "", "1.2 enum only (decided)"},

  {0x1080, "CC_RAIL_CONFIG_NAME",            E, Shape::kText, Shape::kText, "name", "2 CC_RAIL_CONFIG_NAME"},
  {0x1081, "CC_RAIL_CONFIG_BACKLIGHT",       E, Shape::kU8, Shape::kU8, "level", "2 CC_RAIL_CONFIG_BACKLIGHT"},
  {0x1082, "CC_RAIL_CONFIG_MODE",            E, Shape::kRailMode, Shape::kRailMode, "mode", "2 CC_RAIL_CONFIG_MODE"},
  {0x1083, "CC_RAIL_CONFIG_UNITS",           E, Shape::kUnits, Shape::kUnits, "units", "2 CC_RAIL_CONFIG_UNITS"},
  {0x1084, "CC_RAIL_CONFIG_TORQUE",          E, Shape::kU8, Shape::kU8, "level", "2 CC_RAIL_CONFIG_TORQUE"},
  {0x1085, "CC_RAIL_CONFIG_NUM_STEPS",       E, Shape::kU16, Shape::kU16, "steps",
   "2 CC_RAIL_CONFIG_NUM_STEPS; ERRATA 3.4 (u16)"},
  {0x1086, "CC_RAIL_CONFIG_NUM_PULSES",      E, Shape::kU16, Shape::kU16, "pulses", "2 CC_RAIL_CONFIG_NUM_PULSES"},
  {0x1087, "CC_RAIL_CONFIG_TOTAL_DISTANCE",  Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_TOTAL_DISTANCE"},
  {0x1088, "CC_RAIL_CONFIG_DISTANCE_PER_STEP", Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_DISTANCE_PER_STEP"},
  {0x1089, "CC_RAIL_CONFIG_SETTLE_TIME",     E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_SETTLE_TIME"},
  {0x108A, "CC_RAIL_CONFIG_OFF_TIME",        E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_OFF_TIME"},
  {0x108B, "CC_RAIL_CONFIG_SPEED",           Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "speed",
   "2 CC_RAIL_CONFIG_STACK_SPEED"},
  {0x108C, "CC_RAIL_CONFIG_RAMP_TIME",       E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_RAMP_TIME"},
  {0x108D, "CC_RAIL_CONFIG_DISTANCE_PER_REV", Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_DISTANCE_PER_REV (read table: no units byte)"},
  {0x108E, "CC_RAIL_CONFIG_SHUTTER_DISABLE", E, Shape::kBool, Shape::kBool, "enabled", "2 CC_RAIL_CONFIG_SHUTTER_DISABLE"},
  {0x108F, "CC_RAIL_CONFIG_AUTO_RETURN",     E, Shape::kBool, Shape::kBool, "enabled",
   "2 CC_RAIL_CONFIG_AUTO_RETURN (read table garbled: bool in the request)"},
  {0x1090, "CC_RAIL_CONFIG_SAVE",            N, N, Shape::kU8, "slot", "2 CC_RAIL_CONFIG_SAVE"},
  {0x1091, "CC_RAIL_CONFIG_LOAD",            N, N, Shape::kU8, "slot", "2 CC_RAIL_CONFIG_LOAD"},
  {0x1092, "CC_RAIL_CONFIG_AXIS",            E, Shape::kU8, Shape::kU8, "axis", "2 CC_RAIL_CONFIG_AXIS"},
  {0x1093, "CC_RAIL_CONFIG_TIMELAPSE",       E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_TIMELAPSE"},
  {0x1094, "CC_RAIL_CONFIG_PULSE_TIME",      E, Shape::kF32, Shape::kF32, "seconds", "2 CC_RAIL_CONFIG_PULSE_TIME"},
  {0x1095, "CC_RAIL_CONFIG_BACKLASH",        Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "distance",
   "2 CC_RAIL_CONFIG_BACKLASH"},
  {0x1096, "CC_RAIL_CONFIG_HOLDING_TORQUE",  E, Shape::kU8, Shape::kU8, "level", "2 CC_RAIL_CONFIG_HOLDING_TORQUE"},
  {0x1097, "CC_RAIL_CONFIG_SPEED_MOVE",      Shape::kUnitsQuery, Shape::kUnitsF32, Shape::kUnitsF32, "speed",
   "2 CC_RAIL_CONFIG_MOVE_SPEED"},
  {0x1098, "CC_RAIL_CONFIG_POLARITY",        E, Shape::kBool, Shape::kBool, "reverse", "2 CC_RAIL_CONFIG_POLARITY"},
  // No table: one byte each, values from the enum comments.
  {0x1099, "CC_RAIL_CONFIG_IO_MODE",         E, Shape::kIoMode, Shape::kIoMode, "io-mode", "1.2 enum only (decided)"},
  {0x109A, "CC_RAIL_CONFIG_IO_DIR",          E, Shape::kDirection, Shape::kDirection, "io-dir", "1.2 enum only (decided)"},
  {0x109B, "CC_RAIL_CONFIG_ROTARY_BACKLASH", E, Shape::kF32, Shape::kF32, "degrees", "2 CC_RAIL_CONFIG_ROTARY_BACKLASH"},
  {0x109C, "CC_RAIL_CONFIG_ROTARY_RATIO",    E, Shape::kF32, Shape::kF32, "ratio", "2 CC_RAIL_CONFIG_ROTARY_RATIO"},
  {0x109D, "CC_RAIL_CONFIG_ROTARY_DEGREES",  E, Shape::kF32, Shape::kF32, "degrees", "2 CC_RAIL_CONFIG_ROTARY_DEGREES"},
  {0x109E, "CC_RAIL_CONFIG_GLOBAL_MODE",     E, Shape::kGlobalMode, Shape::kGlobalMode, "global-mode",
   "2 CC_RAIL_CONFIG_GLOBAL_MODE"},
  {0x109F, "CC_RAIL_CONFIG_TOFF_FINAL",      E, Shape::kBool, Shape::kBool, "enabled", "2 CC_RAIL_CONFIG_TOFF_FINAL"},
  {0x10A0, "CC_RAIL_CONFIG_SHUTTER",         E, Shape::kShutterSetting, Shape::kShutterSetting, "shutter",
   "2 CC_RAIL_CONFIG_SHUTTER"},

  {0x1100, "CC_RESET",                       N, N, E, "", "2 CC_RESET"},
  {0x1101, "CC_REFLASH",                     N, N, E, "", "2 CC_REFLASH"},
  {0x1102, "CC_SOFTWARE_STRING",             E, Shape::kText, N, "version", "2 CC_SOFTWARE_STRING"},
  {0x1103, "CC_SOFTWARE_ID",                 E, Shape::kU32, N, "id", "2 CC_SOFTWARE_ID"},
  {0x1104, "CC_HARDWARE_ID",                 E, Shape::kU32, N, "id", "2 CC_HARDWARE_ID"},
  {0x1105, "CC_BOOTLOADER_ID",               E, Shape::kU32, N, "id", "2 CC_BOOTLOADER_ID"},
  {0x1106, "CC_SOFTWARE_CHECKSUM",           E, Shape::kU32, N, "checksum", "2 CC_SOFTWARE_CHECKSUM"},
  {0x1107, "CC_SERIAL_NUMBER",               E, Shape::kU32, Shape::kU32, "serial", "2 CC_SERIAL_NUMBER"},
  {0x1108, "CC_NVM_ACCESS",                  Shape::kNvmRead, Shape::kU32, Shape::kNvmWrite, "value",
   "2 CC_NVM_ACCESS (registers 0-127; 1.1.17 says 0-31)"},
  // Unimplemented on the device: no layout, data carried as is.
  {0x1109, "CC_NAND_ACCESS",                 Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "1.2 enum (unimplemented)"},
  {0x110A, "CC_NOR_ACCESS",                  Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "1.2 enum (unimplemented)"},
  {0x110B, "CC_PING",                        Shape::kPingRequest, Shape::kPingReply, N, "",
   "2 CC_PING (table id 0x110A, enum 0x110B)"},
  {0x110C, "CC_LOG",                         Shape::kLogRequest, Shape::kText, N, "entry", "2 CC_LOG"},
  {0x110D, "CC_WIFI",                        Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "1.2 enum only (no layout)"},
  {0x110E, "CC_CLOSE",                       N, N, E, "", "2 CC_CLOSE"},
  {0x1200, "CC_WAD",                         Shape::kRaw, Shape::kRaw, Shape::kRaw, "", "ERRATA 3.10 (no layout)"},
  {0x1600, "CC_MOTION_CONFIG",               N, N, Shape::kMotionConfig, "", "2 CC_MOTION_CONFIG; ERRATA 3.5"},
  {0x1601, "CC_MOTION_START",                N, N, Shape::kMotionStart, "", "2 CC_MOTION_START (3 bytes)"},
};
// clang-format on

constexpr bool TableSorted() {
  for (size_t i = 1; i < std::size(kCommands); ++i) {
    if (kCommands[i - 1].id >= kCommands[i].id) return false;
  }
  return true;
}
static_assert(TableSorted(), "FindCommand binary-searches the table");

}  // namespace

// ---------------------------------------------------------------------------
// Command table access
// ---------------------------------------------------------------------------
const CommandInfo* FindCommand(uint16_t id) {
  const auto* it = std::lower_bound(std::begin(kCommands), std::end(kCommands), id,
                                    [](const CommandInfo& c, uint16_t v) { return c.id < v; });
  if (it == std::end(kCommands) || it->id != id) return nullptr;
  return it;
}

std::span<const CommandInfo> AllCommands() { return kCommands; }

}  // namespace moco::stackshot
