// Wire constants of the Cognisys StackShot / StackShot 3X binary protocol
// (stackshot-protocol.txt sections 1.2, 1.3, 2 and 4; ERRATA.md part 3).
//
// Command ids. The enum listing in section 1.2 (comm_cmd_t) and the per-command
// tables of section 2 disagree in two places; the readings taken here:
//  * CC_RAIL_CONFIG_HOLDING_TORQUE. The tables give HOLDING_TORQUE 0x1096,
//    MOVE_SPEED 0x1097, POLARITY 0x1098, ROTARY_BACKLASH 0x109B, ROTARY_RATIO
//    0x109C, ROTARY_DEGREES 0x109D, GLOBAL_MODE 0x109E, TOFF_FINAL 0x109F and
//    SHUTTER 0x10A0. Counting the enum listing gives each of those one less and
//    has no HOLDING_TORQUE at all. Every table id agrees with the listing once
//    HOLDING_TORQUE is inserted after CC_RAIL_CONFIG_BACKLASH (0x1095), and
//    published host headers declare it exactly there, so the listing omits
//    the entry: HOLDING_TORQUE = 0x1096 and the table ids stand. This also
//    places IO_MODE at 0x1099 and IO_DIR at 0x109A, which have no table.
//  * CC_PING. Its table says 0x110A; counting the listing (NVM_ACCESS 0x1108,
//    NAND_ACCESS, NOR_ACCESS, PING, LOG, WIFI, CLOSE) gives 0x110B. The tables
//    of LOG (0x110C) and CLOSE (0x110E) agree with the count, and published
//    host headers declare PING after NAND and NOR as well, so 0x110A is the
//    table's slip (it is NOR_ACCESS): kPing = 0x110B. A host that followed the
//    table sends 0x110A; the decoder takes a one-byte READ of 0x110A as a ping
//    (see DecodeOptions in stackshot.h) and keeps the id it received.
//  * Names follow the enum listing where the table renames a command:
//    the table's CC_RAIL_CONFIG_STACK_SPEED is CC_RAIL_CONFIG_SPEED (0x108B),
//    its CC_RAIL_CONFIG_MOVE_SPEED is CC_RAIL_CONFIG_SPEED_MOVE (0x1097).
#ifndef MOCO_WIRE_STACKSHOT_CONSTANTS_H_
#define MOCO_WIRE_STACKSHOT_CONSTANTS_H_

#include <cstddef>
#include <cstdint>

#include "wire/stackshot_timing.h"

namespace moco::stackshot {

// --- Framing (section 2, ERRATA 3.1) ----------------------------------------
// Sync, command MSB, command LSB, action/status, data length, data, checksum.
inline constexpr uint8_t kSyncHost = 0x55;    // "0x55 (PC)"
inline constexpr uint8_t kSyncDevice = 0xAA;  // "0xAA (Slave)"
inline constexpr size_t kHeaderBytes = 5;     // sync .. data length
inline constexpr size_t kChecksumBytes = 1;
inline constexpr size_t kMaxDataBytes = 255;  // the length field is one byte
inline constexpr size_t kMinPacketBytes = kHeaderBytes + kChecksumBytes;                  // 6
inline constexpr size_t kMaxPacketBytes = kHeaderBytes + kMaxDataBytes + kChecksumBytes;  // 261
// Byte offsets inside a packet.
inline constexpr size_t kOffsetSync = 0;
inline constexpr size_t kOffsetCommand = 1;  // big-endian u16
inline constexpr size_t kOffsetAction = 3;
inline constexpr size_t kOffsetLength = 4;
inline constexpr size_t kOffsetData = 5;

// Action/status byte (section 2, ERRATA 3.3): low nibble = comm_action_t,
// bits 4-5 = axis (StackShot 3X), bit 7 = second sub-item of a shutter output.
// Bit 6 is not described; it is carried through unchanged.
inline constexpr uint8_t kActionMask = 0x0F;
inline constexpr uint8_t kAxisShift = 4;
inline constexpr uint8_t kAxisMask = 0x30;
inline constexpr uint8_t kReservedBit6 = 0x40;
inline constexpr uint8_t kSubItemBit = 0x80;

// The 2 ms inter-frame gap (section 2) is in stackshot_timing.h.

// --- Section 1.3 defines ----------------------------------------------------
inline constexpr size_t kCommBufferSize = 40;  // COMM_BUFFER_SIZE
// STACKSHOT_BAUD_RATE is kBaudRate in stackshot_timing.h.

// Rail status bits of CC_RAIL_STATUS (u32 bit field).
inline constexpr uint32_t kRailStatusIdle = 0x00;
inline constexpr uint32_t kRailStatusMoving = 0x01;
inline constexpr uint32_t kRailStatusShutter = 0x02;
inline constexpr uint32_t kRailStatusUserAborted = 0x04;  // sticky, clears once read

// --- Section 4 Wi-Fi (ERRATA 3.7, 3.8) --------------------------------------
inline constexpr uint16_t kWifiDiscoveryUdpPort = 24869;  // host broadcasts "FINDSTACK"
inline constexpr uint16_t kWifiHostTcpPort = 24870;       // host listens, controller connects
inline constexpr char kWifiDiscoveryMessage[] = "FINDSTACK";
inline constexpr size_t kWifiMaxPacketBytes = 1000;
static_assert(kMaxPacketBytes <= kWifiMaxPacketBytes,
              "one serial packet always fits a Wi-Fi packet, so the codec never splits one");

// NVM registers: section 1.1.17/1.1.18 allow 0-31, the CC_NVM_ACCESS table
// 0-127. The codec carries any u8; a device picks its own bound.
inline constexpr uint8_t kNvmRegisterCountApi = 32;
inline constexpr uint8_t kNvmRegisterCountSerial = 128;
// CC_RAIL_CONFIG_SAVE / LOAD slots: 0 = power-on configuration, 1-10 user slots.
inline constexpr uint8_t kConfigSlotMax = 10;
inline constexpr uint32_t kUnprogrammed = 0xFFFFFFFF;  // serial number / NVM register

// --- comm_cmd_t (section 1.2 with the readings above) -----------------------
enum class Command : uint16_t {
  kRailMove = 0x1000,
  kRailPositionTarget = 0x1001,
  kRailPositionCurrent = 0x1002,
  kRailPositionZero = 0x1003,
  kRailShutterFire = 0x1004,
  kRailStatus = 0x1005,
  kRailStop = 0x1006,
  kRailMoveAtSpeed = 0x1007,
  // StackShot 3X additions.
  kRailStack = 0x1008,
  kRailStackStatus = 0x1009,
  kRailStackPosition = 0x100A,
  kRailStopRamp = 0x100B,

  kRailConfigName = 0x1080,
  kRailConfigBacklight = 0x1081,
  kRailConfigMode = 0x1082,
  kRailConfigUnits = 0x1083,
  kRailConfigTorque = 0x1084,
  kRailConfigNumSteps = 0x1085,
  kRailConfigNumPulses = 0x1086,
  kRailConfigTotalDistance = 0x1087,
  kRailConfigDistancePerStep = 0x1088,
  kRailConfigSettleTime = 0x1089,
  kRailConfigOffTime = 0x108A,
  kRailConfigSpeed = 0x108B,  // table: CC_RAIL_CONFIG_STACK_SPEED
  kRailConfigRampTime = 0x108C,
  kRailConfigDistancePerRev = 0x108D,
  kRailConfigShutterDisable = 0x108E,
  kRailConfigAutoReturn = 0x108F,
  kRailConfigSave = 0x1090,
  kRailConfigLoad = 0x1091,
  kRailConfigAxis = 0x1092,
  kRailConfigTimelapse = 0x1093,
  kRailConfigPulseTime = 0x1094,
  kRailConfigBacklash = 0x1095,
  kRailConfigHoldingTorque = 0x1096,  // in the tables, missing from the enum listing
  // StackShot 3X additions.
  kRailConfigSpeedMove = 0x1097,  // table: CC_RAIL_CONFIG_MOVE_SPEED
  kRailConfigPolarity = 0x1098,
  kRailConfigIoMode = 0x1099,
  kRailConfigIoDir = 0x109A,
  kRailConfigRotaryBacklash = 0x109B,
  kRailConfigRotaryRatio = 0x109C,
  kRailConfigRotaryDegrees = 0x109D,
  kRailConfigGlobalMode = 0x109E,
  kRailConfigToffFinal = 0x109F,
  kRailConfigShutter = 0x10A0,

  kReset = 0x1100,
  kReflash = 0x1101,
  kSoftwareString = 0x1102,
  kSoftwareId = 0x1103,
  kHardwareId = 0x1104,
  kBootloaderId = 0x1105,
  kSoftwareChecksum = 0x1106,
  kSerialNumber = 0x1107,
  kNvmAccess = 0x1108,
  // StackShot 3X additions.
  kNandAccess = 0x1109,  // unimplemented on the device
  kNorAccess = 0x110A,   // unimplemented on the device; CC_PING's table id
  kPing = 0x110B,        // table says 0x110A, see above
  kLog = 0x110C,
  kWifi = 0x110D,
  kClose = 0x110E,

  kWad = 0x1200,  // composite message, no layout (ERRATA 3.10)

  kMotionConfig = 0x1600,
  kMotionStart = 0x1601,
};
// The id CC_PING's table gives; see the file comment.
inline constexpr uint16_t kPingTableId = 0x110A;

constexpr uint16_t Id(Command c) { return static_cast<uint16_t>(c); }

// --- comm_action_t: low nibble of the action/status byte --------------------
enum class Action : uint8_t {
  kRead = 0,
  kWrite = 1,
  kRspOk = 2,
  kBadParam = 3,
  kUnsupportedAction = 4,
  kUnsupportedCmd = 5,
  kFailed = 6,
  kNotEmpty = 7,
  kBusy = 8,
};
inline constexpr uint8_t kActionMax = 9;  // COMM_ACTION_MAX

// --- comm_rail_dir_t ---------------------------------------------------------
enum class Direction : uint8_t { kForward = 0, kBack = 1 };
inline constexpr uint8_t kDirectionMax = 2;

// --- comm_rail_units_t -------------------------------------------------------
// The spec lists ENGLISH (mils), METRIC (mm), STEPS. Published host headers of
// later firmware add DEGREES = 3 for rotary moves; it is named here so that
// transcripts read well, and a device decides whether to accept it.
enum class Units : uint8_t { kMils = 0, kMm = 1, kSteps = 2, kDegrees = 3 };
inline constexpr uint8_t kUnitsMaxSpec = 3;  // COMM_RAIL_UNITS_MAX of the spec

// --- comm_rail_mode_t (stacking mode, CC_RAIL_CONFIG_MODE) -------------------
// 0-5 from the enum listing; revision 1.1 notes add "Config->Mode: Rotary (7)",
// and host headers name 6 MANUAL_DISTANCE and 7 ROTARY.
enum class RailMode : uint8_t {
  kAutoStep = 0,
  kAutoDist = 1,
  kTotalDistance = 2,
  kDistancePerStep = 3,
  kManual = 4,
  kContinuous = 5,
  kManualDistance = 6,
  kRotary = 7,
};

// --- setting_global_mode_t (CC_RAIL_CONFIG_GLOBAL_MODE) ----------------------
enum class GlobalMode : uint8_t {
  kAdvanced = 0,
  kStackPano2x = 1,
  kStackPano3x = 2,
  kStackRotate2x = 3,
  kStackRotate3x = 4,
  kPano1x = 5,
  kPano2x = 6,
  kPano1x360 = 7,
  kMotionDfMoco = 8,
  kMotionReserved = 9,
  kMotionContinuous = 10,
  kMotionContTimelapse = 11,
  kMotionSms = 12,
};
inline constexpr uint8_t kGlobalModeMax = 13;

// --- setting_shutter_t (CC_RAIL_CONFIG_SHUTTER) -------------------------------
enum class ShutterSetting : uint8_t { kNone = 0, kShutter1 = 1, kShutter2 = 2, kBoth = 3 };
inline constexpr uint8_t kShutterSettingMax = 4;

// --- setting_axis_t (CC_MOTION_CONFIG bytes 0-3, a u32 on the wire) ----------
enum class AxisType : uint32_t { kSlider = 0, kRail = 1, kRotary = 2 };
inline constexpr uint32_t kAxisTypeMax = 3;

// --- I/O mode and direction (CC_RAIL_CONFIG_IO_MODE / IO_DIR) -----------------
// Named in revision 1.1 (setting_io_t, setting_io_dir_t) without values; the
// enum comments say "Normal, master, slave" and "FWD or BACK".
enum class IoMode : uint8_t { kNormal = 0, kMaster = 1, kSlave = 2 };
inline constexpr uint8_t kIoModeMax = 3;

// --- comm_rail_axis_t (API level: StackShot_Open, NVM register 0) ------------
enum class RailAxis : uint8_t { kAny = 0, kX = 1, kY = 2, kZ = 3, kUndefined = 4 };

// Axis numbers in bits 4-5 of the action byte (StackShot 3X).
inline constexpr uint8_t kAxisX = 0;
inline constexpr uint8_t kAxisY = 1;
inline constexpr uint8_t kAxisZ = 2;

// --- CC_MOTION_CONFIG layout (ERRATA 3.5) ------------------------------------
inline constexpr size_t kBezierCurves = 4;
inline constexpr size_t kBezierPoints = 4;
inline constexpr size_t kMotionConfigBytes = 4 + kBezierCurves * kBezierPoints * 8;  // 132
// Offset of point p of curve c (x; y follows 4 bytes later).
constexpr size_t BezierPointOffset(size_t curve, size_t point) {
  return 4 + 32 * curve + 8 * point;
}
static_assert(kMotionConfigBytes == 132);
static_assert(BezierPointOffset(3, 3) + 8 == kMotionConfigBytes);

// --- Fixed payload sizes from the tables ---------------------------------------
inline constexpr size_t kRailMoveBytes = 7;
inline constexpr size_t kRailMoveAtSpeedBytes = 10;
inline constexpr size_t kShutterFireBytes = 10;
inline constexpr size_t kRailStackBytes = 48;           // table "Length: 48"
inline constexpr size_t kRailStackListedBytes = 44;     // fields the table lists
inline constexpr size_t kMotionStartBytes = 3;          // table "Length: 132" is a copy slip
inline constexpr size_t kMotionStartListedBytes = 132;  // the header's Length, also accepted

}  // namespace moco::stackshot

#endif  // MOCO_WIRE_STACKSHOT_CONSTANTS_H_
