// Wire constants of the DMC v2 protocol (dmc-v2-protocol.txt "Message Format",
// "Message Types", "Capabilities"; ERRATA dmc 1-11; FACTS "DMC v2" and "Boom rig").
// Names mirror the spec's MSG_* / ACK_* names; values are the on-wire values.
// The line's speed and the protocol's timing are in dmc_timing.h (included).
#ifndef MOCO_WIRE_DMC_CONSTANTS_H_
#define MOCO_WIRE_DMC_CONSTANTS_H_

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "wire/dmc_timing.h"

namespace moco::dmc {

// --- Frame layout ("Message Format"; ERRATA 1.1, 1.2) -------------------------
inline constexpr uint8_t kMarker0 = 'D';
inline constexpr uint8_t kMarker1 = 'F';
inline constexpr size_t kMarkerSize = 2;
inline constexpr size_t kIdOffset = 2;      // u32 app-defined message id
inline constexpr size_t kTypeOffset = 6;    // u16 message type
inline constexpr size_t kLengthOffset = 8;  // u16 length of the data section
inline constexpr size_t kHeaderSize = 10;   // marker + id + type + length
inline constexpr size_t kCheckSize = 2;     // two Fletcher check bytes after the data
// "The receiving buffer on the device must be at least 1048 bytes."
inline constexpr size_t kReceiveBufferSize = 1048;
// ERRATA 1.2: 1048 - header - check bytes. A larger Length is a framing error.
inline constexpr size_t kMaxDataLength = kReceiveBufferSize - kHeaderSize - kCheckSize;  // 1036
inline constexpr size_t kMaxFrameSize = kHeaderSize + kMaxDataLength + kCheckSize;       // 1048
// The spec's 1048 is a minimum: a device may hold more (FACTS: dmc-lite holds
// 2048) and then waits for a Length that a 1048-byte receiver drops. The
// largest receive buffer a FrameDecoder (and a DMC-16 profile) models.
inline constexpr size_t kLargestReceiveBuffer = 4096;
// Fletcher-16 is summed in blocks of this many bytes before reducing mod 255
// ("Computing and Validating the Checksum").
inline constexpr size_t kFletcherBlock = 20;
inline constexpr uint16_t kFletcherModulus = 0xff;

// --- Message types ("Message Types") --------------------------------------------
// Set on the Type of an ACK response: the Data holds a response code.
inline constexpr uint16_t kFlagAck = 0x8000;
// FACTS: the reference parser (dmc-lite) drops frames whose type has bits
// outside this mask. The framing layer here keeps them (the device answers
// ERR_UNSUPPORTED); see HasReferenceParserType().
inline constexpr uint16_t kReferenceTypeMask = 0x83ff;

enum class MsgType : uint16_t {
  kHi = 0x0001,
  kDmx = 0x0020,
  kGioOut = 0x0021,
  kGioIn = 0x0022,
  kGioCam = 0x0023,
  kMotorStatus = 0x0030,
  kMotorMove = 0x0031,
  kMotorStop = 0x0032,
  kMotorStopAll = 0x0033,
  kMotorGetPosition = 0x0034,
  kMotorResetPosition = 0x0035,
  kMotorJog = 0x0036,
  kMotorConfigure = 0x0037,
  kMotorSetSpeed = 0x0038,
  kMotorSetLimits = 0x0039,
  kMotorHardStop = 0x003a,
  kRtUploadMoveBegin = 0x0100,
  kRtUploadMoveAxis = 0x0101,
  kRtUploadMoveDmx = 0x0102,
  kRtUploadMoveEnd = 0x0103,
  kRtUploadMoveTriggers = 0x0104,
  kRtPositionFrame = 0x0110,
  kRtRunMove = 0x0111,
  kRtShootFrame = 0x0112,
  kRtGo = 0x0113,
  kRtEnd = 0x0114,
  kRtShootFrame2 = 0x0115,  // "MSG_GO_MOTION2" in the capability list (ERRATA 1.8)
  kRtStopLoop = 0x0116,
  kRtJogAll = 0x0120,
  kVirtConfig = 0x0200,
  kVirtMove = 0x0201,
  kVirtStop = 0x0202,
  kVirtJog = 0x0203,
  kVirtGetPosition = 0x0205,
  kVirtJogOnLine = 0x0206,  // was 0x0204 before the 2018-03-10 revision
  kVirtAimPoint = 0x0207,
};

// The type MSG_VIRT_JOG_ON_LINE had before the 2018-03-10 revision. Not a
// current message: it decodes as an unknown type.
inline constexpr uint16_t kLegacyVirtJogOnLineType = 0x0204;

constexpr uint16_t ToWire(MsgType t) { return static_cast<uint16_t>(t); }

// The name functions below are defined in dmc_frame.cpp (library moco_wire).

// True when `type` names one of the MsgType values above (without the ACK flag).
bool IsKnownType(uint16_t type);

// The spec's name without the "MSG_" prefix ("MOTOR_MOVE"), with "ACK " in
// front when kFlagAck is set, or "0x%04x" for an unknown type.
std::string TypeName(uint16_t type);

// FACTS: the reference parser accepts a frame only when the type has no bits
// outside 0x83FF. Frames failing this are still delivered by FrameDecoder.
constexpr bool HasReferenceParserType(uint16_t type) {
  return (type & static_cast<uint16_t>(~kReferenceTypeMask)) == 0;
}

// --- ACK response codes ("MSG_FLAG_ACK"; FACTS for 0x0019) ------------------------
enum class AckCode : uint16_t {
  kOk = 0x0010,
  kErrChecksum = 0x0011,
  kErrMoving = 0x0012,
  kErrUnsupported = 0x0013,
  kErrRange = 0x0014,
  kErrGeneral = 0x0015,
  kErrNotInPosition = 0x0016,
  kErrPreroll = 0x0017,
  kErrPostroll = 0x0018,
  kErrAimPoint = 0x0019,  // FACTS: dmc-lite only, aim-point failure
  kErrSoftUp = 0x0020,
  kErrSoftLow = 0x0021,
  kErrHardUp = 0x0022,
  kErrHardLow = 0x0023,
};

constexpr uint16_t ToWire(AckCode c) { return static_cast<uint16_t>(c); }

// "OK", "ERR_CHECKSUM", ... or "0x%04x" (0x%08x above 0xffff) for an unknown code.
std::string AckCodeName(uint32_t code);

// --- Capabilities (MSG_HI "Capabilities"; FACTS) --------------------------------
inline constexpr uint32_t kCapRealTime = 0x0001;  // upload move / jog all / play
inline constexpr uint32_t kCapGoMotion = 0x0002;  // MSG_RT_SHOOT_FRAME
inline constexpr uint32_t kCapVirtBoomSwingTrack = 0x0004;
inline constexpr uint32_t kCapVirtSwingPan = 0x0008;
inline constexpr uint32_t kCapVirtYSwingTrack = 0x0010;
inline constexpr uint32_t kCapVirtXyz = 0x0020;
inline constexpr uint32_t kCapAimPoint = 0x0040;   // dmc-lite: "object tracking"
inline constexpr uint32_t kCapGoMotion2 = 0x0080;  // MSG_RT_SHOOT_FRAME2
inline constexpr uint32_t kCapCoupleMotors = 0x0100;
inline constexpr uint32_t kCapRtLooping = 0x0200;        // loop / ping-pong playback
inline constexpr uint32_t kCapRtCameraTrigger = 0x0400;  // video or stills trigger

// --- MSG_HI response (ERRATA 1.3; FACTS: older devices omit PROTOCOL VERSION) -----
inline constexpr size_t kHiNameSize = 32;
inline constexpr size_t kHiResponseSize = 51;
inline constexpr size_t kHiResponseLegacySize = 49;  // without PROTOCOL VERSION
inline constexpr uint16_t kProtocolVersion = 2;

// --- Counts ("MSG_HI" field ranges) -------------------------------------------------
inline constexpr uint8_t kMaxMotors = 32;
inline constexpr uint16_t kMaxDmxChannels = 512;
inline constexpr uint8_t kMaxGio = 32;

// --- MSG_GIO_CAM flags ----------------------------------------------------------------
inline constexpr uint32_t kGioCamShutter = 0x0001;
inline constexpr uint32_t kGioCamMeter = 0x0002;

// --- MSG_MOTOR_STOP_ALL flags -----------------------------------------------------------
inline constexpr uint32_t kStopAllSilent = 0x01;  // do not flash warnings on the device

// --- MSG_MOTOR_JOG / MSG_VIRT_JOG / MSG_VIRT_JOG_ON_LINE speeds ---------------------------
inline constexpr uint16_t kJogSpeedInch = 1;
inline constexpr uint16_t kJogSpeedMax = 10000;

// --- MSG_MOTOR_CONFIGURE flags (spec: 0x01, 0x02; FACTS: the rest) -------------------------
inline constexpr uint8_t kMotorEnabled = 0x01;
inline constexpr uint8_t kMotorBlurEnabled = 0x02;
inline constexpr uint8_t kMotorVirtualAxis = 0x04;  // axis used in virtuals
inline constexpr uint8_t kMotorLiveControl = 0x08;
inline constexpr uint8_t kMotorCoupled = 0x10;
inline constexpr uint8_t kMotorCoupledReversed = 0x20;

// --- MSG_MOTOR_SET_LIMITS ---------------------------------------------------------------------
inline constexpr uint8_t kLimitEnabled = 0x01;
inline constexpr uint8_t kHwSetSwapHighLow = 0x80;  // in HW SET: swaps high/low inputs

// --- MSG_MOTOR_HARD_STOP reasons (MOTOR present only for 1 and 2) ------------------------------
enum class HardStopReason : uint8_t {
  kEStop = 0,  // E-Stop / general
  kUpperLimit = 1,
  kLowerLimit = 2,
  kEngineException = 100,
};
constexpr bool HardStopHasMotor(uint8_t reason) { return reason == 1 || reason == 2; }
// "E_STOP", "UPPER_LIMIT", "LOWER_LIMIT", "ENGINE_EXCEPTION" or the number.
std::string HardStopReasonName(uint8_t reason);

// --- Real-time moves ---------------------------------------------------------------------------
// START INDEX of RT_UPLOAD_MOVE_AXIS / _DMX: this is the last set for the channel.
inline constexpr uint32_t kLastSetFlag = 0x80000000u;
inline constexpr uint32_t kStartIndexMask = 0x7fffffffu;
// RT_RUN_MOVE FLAGS (spec; FACTS "playback flags").
inline constexpr uint16_t kPlayPingPong = 0x01;
inline constexpr uint16_t kPlayLoop = 0x02;
inline constexpr uint16_t kPlayCameraVideo = 0x10;   // trigger at start/stop of move
inline constexpr uint16_t kPlayCameraStills = 0x20;  // trigger every frame
// RT_SHOOT_FRAME DIRECTION.
inline constexpr uint8_t kDirectionForward = 1;
inline constexpr uint8_t kDirectionBackward = 0;
// Scales on the wire.
inline constexpr uint32_t kFpsScale = 1000;        // FPS * 1000
inline constexpr uint32_t kMoveTimeScale = 1000;   // thousandths of a frame
inline constexpr uint16_t kBlurPercentScale = 10;  // percentage * 10

// --- Virtuals (MSG_VIRT_*; FACTS "Boom rig virtual axes") ---------------------------------------
inline constexpr int32_t kVirtPositionScale = 100000;    // positions and angles * 100000
inline constexpr int32_t kVirtLengthScale = 1000;        // lengths and aim coordinates * 1000
inline constexpr size_t kBoomCompensationEntries = 121;  // -60..+60 degrees, 1 degree apart
inline constexpr int kBoomCompensationFirstDeg = -60;

// Virtual motor numbers of VIRT_MOVE / VIRT_STOP / VIRT_JOG (FACTS).
enum class VirtAxis : uint8_t {
  kTrack = 1,
  kEw = 2,
  kNs = 3,
  kPan = 4,
  kTilt = 5,
  kRoll = 6,
};

// AXIS of VIRT_JOG_ON_LINE.
enum class JogLineAxis : uint8_t {
  kX = 0,
  kY = 1,
  kZ = 2,  // camera line
  kPan = 3,
  kTilt = 4,
};

// TYPE of VIRT_CONFIG. The spec numbers the rigs 0..4; FACTS: a dmc-lite-derived
// firmware uses bit flags, agreeing for 1 and 2 and sending 8 for x-y-z.
enum class RigType : uint8_t {
  kNone = 0,
  kBoomSwingTrack = 1,
  kSwingPan = 2,
  kYSwingTrack = 3,
  kXyz = 4,
  kXyzFlag = 8,  // FACTS: x-y-z as one firmware numbers it
};

}  // namespace moco::dmc

#endif  // MOCO_WIRE_DMC_CONSTANTS_H_
