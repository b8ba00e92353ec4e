// DMC v2 messages (dmc-v2-protocol.txt "Message Types", every MSG_* section;
// ERRATA dmc 1.3-1.11; FACTS "DMC v2"): typed structs for both directions,
// decode from a Frame, encode to a complete frame, one-line descriptions.
//
// The same Type has different layouts per direction, so there are two sum
// types: HostMessage (what Dragonframe sends) and DeviceMessage (what a device
// sends, solicited or not). Decoding is by layout only: field values are kept
// as received (motor 0, channel 600, unknown flag bits...) and judged by the
// device, so that every decoded message re-encodes to the same data bytes.
// Decode errors carry offsets counted from the first byte of the data section.
#ifndef MOCO_WIRE_DMC_H_
#define MOCO_WIRE_DMC_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "wire/bytes.h"
#include "wire/dmc_constants.h"
#include "wire/dmc_frame.h"

namespace moco::dmc {

// --- Both directions ---------------------------------------------------------------

// How many bytes carry the response code of an ACK: the spec's WORD, or the
// 32-bit value one dmc-lite-based firmware writes (FACTS).
enum class AckWidth : uint8_t { k16 = 2, k32 = 4 };

// "MSG_FLAG_ACK": Type = request Type | kFlagAck, ID = request ID, Data = code.
struct Ack {
  uint16_t type = 0;                     // the acknowledged type, without kFlagAck
  uint32_t code = ToWire(AckCode::kOk);  // REQUIRES: <= 0xffff when width is k16
  AckWidth width = AckWidth::k16;

  bool operator==(const Ack&) const = default;
};

// A Type this direction has no layout for. Never has kFlagAck set.
struct Unknown {
  uint16_t type = 0;
  Bytes data;

  bool operator==(const Unknown&) const = default;
};

// MSG_VIRT_AIM_POINT, request and response alike (same layout, 13 bytes).
struct VirtAimPoint {
  static constexpr MsgType kType = MsgType::kVirtAimPoint;
  uint8_t enable = 0;
  int32_t x_x1000 = 0;  // x kVirtLengthScale on the wire
  int32_t y_x1000 = 0;
  int32_t z_x1000 = 0;

  bool operator==(const VirtAimPoint&) const = default;
};

// --- Requests (Dragonframe -> device) -----------------------------------------------

struct HiRequest {
  static constexpr MsgType kType = MsgType::kHi;
  bool operator==(const HiRequest&) const = default;
};

// MSG_DMX: RAMP, START CHANNEL (1-512), one or more LIGHT VALUEs.
struct Dmx {
  static constexpr MsgType kType = MsgType::kDmx;
  uint8_t ramp = 0;  // 1 = ramp, 0 = immediate
  uint16_t start_channel = 1;
  std::vector<uint8_t> values;  // REQUIRES: 1..kMaxDataLength - 3 values

  bool operator==(const Dmx&) const = default;
};

struct GioOut {
  static constexpr MsgType kType = MsgType::kGioOut;
  uint32_t triggers = 0;
  bool operator==(const GioOut&) const = default;
};

// ERRATA 1.6: the request carries no data.
struct GioInRequest {
  static constexpr MsgType kType = MsgType::kGioIn;
  bool operator==(const GioInRequest&) const = default;
};

struct GioCam {
  static constexpr MsgType kType = MsgType::kGioCam;
  uint32_t flags = 0;  // kGioCamShutter | kGioCamMeter
  bool operator==(const GioCam&) const = default;
};

struct MotorStatusRequest {
  static constexpr MsgType kType = MsgType::kMotorStatus;
  bool operator==(const MotorStatusRequest&) const = default;
};

struct MotorMove {
  static constexpr MsgType kType = MsgType::kMotorMove;
  uint8_t motor = 1;  // 1-based
  int32_t position_steps = 0;
  bool operator==(const MotorMove&) const = default;
};

struct MotorStop {
  static constexpr MsgType kType = MsgType::kMotorStop;
  uint8_t motor = 1;
  bool operator==(const MotorStop&) const = default;
};

// ERRATA 1.7: FLAGS is optional; whether it was sent is kept.
struct MotorStopAll {
  static constexpr MsgType kType = MsgType::kMotorStopAll;
  std::optional<uint32_t> flags;  // kStopAllSilent
  bool operator==(const MotorStopAll&) const = default;
};

struct MotorGetPositionRequest {
  static constexpr MsgType kType = MsgType::kMotorGetPosition;
  bool operator==(const MotorGetPositionRequest&) const = default;
};

struct MotorResetPosition {
  static constexpr MsgType kType = MsgType::kMotorResetPosition;
  uint8_t motor = 1;
  int32_t position_steps = 0;
  bool operator==(const MotorResetPosition&) const = default;
};

struct MotorJog {
  static constexpr MsgType kType = MsgType::kMotorJog;
  uint8_t motor = 1;
  uint16_t speed = kJogSpeedInch;  // 1 = inching .. 10000 = max velocity
  int32_t destination_steps = 0;
  bool operator==(const MotorJog&) const = default;
};

struct MotorConfigure {
  static constexpr MsgType kType = MsgType::kMotorConfigure;
  uint8_t motor = 1;
  uint8_t flags = 0;  // kMotorEnabled, kMotorBlurEnabled, ... (unknown bits kept)
  bool operator==(const MotorConfigure&) const = default;
};

struct MotorSetSpeed {
  static constexpr MsgType kType = MsgType::kMotorSetSpeed;
  uint8_t motor = 1;
  uint32_t max_velocity_steps_per_s = 0;
  uint32_t max_accel_steps_per_s2 = 0;
  bool operator==(const MotorSetSpeed&) const = default;
};

struct MotorSetLimits {
  static constexpr MsgType kType = MsgType::kMotorSetLimits;
  uint8_t motor = 1;
  uint8_t lower_enable = 0;  // kLimitEnabled or 0
  int32_t lower_limit_steps = 0;
  uint8_t upper_enable = 0;
  int32_t upper_limit_steps = 0;
  uint8_t hw_set = 0;  // hardware limit set, 0 = none; kHwSetSwapHighLow swaps
  bool operator==(const MotorSetLimits&) const = default;
};

struct RtUploadMoveBegin {
  static constexpr MsgType kType = MsgType::kRtUploadMoveBegin;
  uint32_t start_frame = 0;
  uint32_t end_frame = 0;
  bool operator==(const RtUploadMoveBegin&) const = default;
};

// START INDEX is split into the index and the kLastSetFlag bit.
struct RtUploadMoveAxis {
  static constexpr MsgType kType = MsgType::kRtUploadMoveAxis;
  uint8_t motor = 1;
  uint32_t start_index = 0;  // REQUIRES: <= kStartIndexMask
  bool last_set = false;
  std::vector<int32_t> positions_steps;  // REQUIRES: 1..257 entries
  bool operator==(const RtUploadMoveAxis&) const = default;
};

struct RtUploadMoveDmx {
  static constexpr MsgType kType = MsgType::kRtUploadMoveDmx;
  uint16_t channel = 1;
  uint32_t start_index = 0;  // REQUIRES: <= kStartIndexMask
  bool last_set = false;
  std::vector<uint8_t> levels;  // REQUIRES: 1..1030 entries
  bool operator==(const RtUploadMoveDmx&) const = default;
};

struct TriggerPoint {
  uint32_t frame_index = 0;  // frame - start
  uint32_t values = 0;
  bool operator==(const TriggerPoint&) const = default;
};

struct RtUploadMoveTriggers {
  static constexpr MsgType kType = MsgType::kRtUploadMoveTriggers;
  uint32_t mask = 0;
  std::vector<TriggerPoint> points;  // REQUIRES: 0..129 entries
  bool operator==(const RtUploadMoveTriggers&) const = default;
};

struct RtUploadMoveEnd {
  static constexpr MsgType kType = MsgType::kRtUploadMoveEnd;
  bool operator==(const RtUploadMoveEnd&) const = default;
};

struct RtPositionFrame {
  static constexpr MsgType kType = MsgType::kRtPositionFrame;
  uint32_t frame = 0;
  bool operator==(const RtPositionFrame&) const = default;
};

// ERRATA 1.7: the fields after BLOOP TIME are optional, each only with the
// ones before it: 29, 31, 33 or 35 data bytes. The form received is kept.
struct RtRunMove {
  static constexpr MsgType kType = MsgType::kRtRunMove;
  uint32_t fps_x1000 = 0;  // x kFpsScale on the wire
  uint32_t start_frame = 0;
  uint32_t end_frame = 0;
  uint32_t preroll_ms = 0;
  uint32_t postroll_ms = 0;
  uint8_t sync_dmx = 0;
  uint32_t bloop_outputs = 0;  // GIO outputs for the bloop signal
  uint16_t bloop_dmx_channel = 0;
  uint16_t bloop_time_ms = 0;
  // REQUIRES: camera_close_angle_deg only with camera_open_angle_deg, that only with flags.
  std::optional<uint16_t> flags;  // kPlayPingPong, kPlayLoop, kPlayCamera*
  std::optional<uint16_t> camera_open_angle_deg;
  std::optional<uint16_t> camera_close_angle_deg;
  bool operator==(const RtRunMove&) const = default;
};

// MOTOR #n, POS A (angle 0), POS B (angle 360) of the shoot-frame messages.
struct BlurMotor {
  uint8_t motor = 1;
  int32_t pos_a_steps = 0;
  int32_t pos_b_steps = 0;
  bool operator==(const BlurMotor&) const = default;
};

struct RtShootFrame {
  static constexpr MsgType kType = MsgType::kRtShootFrame;
  uint32_t frame = 0;
  uint8_t direction = kDirectionForward;
  uint32_t exposure_ms = 0;
  uint16_t blur_percent_x10 = 0;  // x kBlurPercentScale on the wire
  std::vector<BlurMotor> motors;  // REQUIRES: 0..113 entries
  bool operator==(const RtShootFrame&) const = default;
};

struct RtShootFrame2 {
  static constexpr MsgType kType = MsgType::kRtShootFrame2;
  uint32_t frame = 0;
  uint32_t exposure_ms = 0;
  uint16_t open_angle_deg = 0;
  uint16_t close_angle_deg = 0;
  std::vector<BlurMotor> motors;  // REQUIRES: 0..113 entries
  bool operator==(const RtShootFrame2&) const = default;
};

struct RtGo {
  static constexpr MsgType kType = MsgType::kRtGo;
  bool operator==(const RtGo&) const = default;
};

struct RtStopLoop {
  static constexpr MsgType kType = MsgType::kRtStopLoop;
  bool operator==(const RtStopLoop&) const = default;
};

struct RtJogAll {
  static constexpr MsgType kType = MsgType::kRtJogAll;
  uint32_t fps_x1000 = 0;
  uint32_t destination_frame = 0;
  bool operator==(const RtJogAll&) const = default;
};

// One axis of the boom-swing-track configuration: motor, steps per unit,
// position in units x100000. (All DWORDs; spu read as signed, see dmc_layouts.cpp.)
struct VirtAxisSetup {
  uint32_t motor = 0;
  int32_t steps_per_unit = 0;
  int32_t position_x100000 = 0;  // x kVirtPositionScale on the wire
  bool operator==(const VirtAxisSetup&) const = default;
};

// One axis of the swing-pan configuration: motor and steps per unit only.
struct VirtAxisScale {
  uint32_t motor = 0;
  int32_t steps_per_unit = 0;
  bool operator==(const VirtAxisScale&) const = default;
};

struct VirtRigNone {
  bool operator==(const VirtRigNone&) const = default;
};

// TYPE = 1. Data: 93 bytes, + 484 with the compensation table, + 4 with
// SAFE DISTANCE (ERRATA 1.7): 93, 97, 577 or 581 bytes.
struct VirtRigBoomSwingTrack {
  VirtAxisSetup boom, swing, track, pan, tilt, roll;
  int32_t boom_length_x1000 = 0;  // x kVirtLengthScale on the wire
  int32_t boom_ext_x1000 = 0;
  int32_t nodal_x_x1000 = 0;
  int32_t nodal_y_x1000 = 0;
  int32_t nodal_z_x1000 = 0;
  // Boom position at -60, -59, ... +60 degrees.
  std::optional<std::array<int32_t, kBoomCompensationEntries>> compensation;
  std::optional<int32_t> safe_distance_x1000;
  bool operator==(const VirtRigBoomSwingTrack&) const = default;
};

// TYPE = 2.
struct VirtRigSwingPan {
  VirtAxisScale swing, pan;
  bool operator==(const VirtRigSwingPan&) const = default;
};

// Any other TYPE (3 y-swing-track and 4 x-y-z have no layout in the spec;
// 8 is x-y-z for one firmware): the bytes after TYPE, uninterpreted.
struct VirtRigRaw {
  uint8_t type = 0;  // REQUIRES: not 0, 1 or 2
  Bytes data;        // REQUIRES: <= kMaxDataLength - 1 bytes
  bool operator==(const VirtRigRaw&) const = default;
};

struct VirtConfig {
  static constexpr MsgType kType = MsgType::kVirtConfig;
  std::variant<VirtRigNone, VirtRigBoomSwingTrack, VirtRigSwingPan, VirtRigRaw> rig;
  // The TYPE byte on the wire.
  uint8_t rig_type() const;
  bool operator==(const VirtConfig&) const = default;
};

struct VirtMove {
  static constexpr MsgType kType = MsgType::kVirtMove;
  uint8_t axis = 1;  // VirtAxis
  int32_t position_x100000 = 0;
  bool operator==(const VirtMove&) const = default;
};

struct VirtStop {
  static constexpr MsgType kType = MsgType::kVirtStop;
  uint8_t axis = 1;
  bool operator==(const VirtStop&) const = default;
};

// The spec copies MOTOR_JOG's table; DESTINATION is read in the virtual
// axis's units x100000 like VIRT_MOVE's POSITION.
struct VirtJog {
  static constexpr MsgType kType = MsgType::kVirtJog;
  uint8_t axis = 1;
  uint16_t speed = kJogSpeedInch;
  int32_t destination_x100000 = 0;
  bool operator==(const VirtJog&) const = default;
};

// ERRATA 1.10: SPEED is signed, -10000..10000.
struct VirtJogOnLine {
  static constexpr MsgType kType = MsgType::kVirtJogOnLine;
  uint8_t axis = 0;  // JogLineAxis
  int16_t speed = 0;
  bool operator==(const VirtJogOnLine&) const = default;
};

struct VirtGetPositionRequest {
  static constexpr MsgType kType = MsgType::kVirtGetPosition;
  bool operator==(const VirtGetPositionRequest&) const = default;
};

using HostMessage =
    std::variant<Ack, HiRequest, Dmx, GioOut, GioInRequest, GioCam, MotorStatusRequest, MotorMove,
                 MotorStop, MotorStopAll, MotorGetPositionRequest, MotorResetPosition, MotorJog,
                 MotorConfigure, MotorSetSpeed, MotorSetLimits, RtUploadMoveBegin, RtUploadMoveAxis,
                 RtUploadMoveDmx, RtUploadMoveTriggers, RtUploadMoveEnd, RtPositionFrame, RtRunMove,
                 RtShootFrame, RtShootFrame2, RtGo, RtStopLoop, RtJogAll, VirtConfig, VirtMove,
                 VirtStop, VirtJog, VirtJogOnLine, VirtGetPositionRequest, VirtAimPoint, Unknown>;

// --- Responses and unsolicited messages (device -> Dragonframe) -----------------------

// MSG_HI response (ERRATA 1.3): 51 bytes, or 49 without PROTOCOL VERSION (FACTS).
struct HiResponse {
  static constexpr MsgType kType = MsgType::kHi;
  std::array<uint8_t, kHiNameSize> name{};  // UTF-8, \0-filled; kept byte for byte
  uint8_t fw_major = 0;
  uint8_t fw_minor = 0;
  uint8_t fw_rev = 0;
  uint8_t motor_count = 0;  // 0-32
  uint16_t dmx_count = 0;   // 0-512
  uint8_t gio_out_count = 0;
  uint8_t gio_in_count = 0;
  uint8_t hw_limit_count = 0;
  uint32_t upload_frame_count = 0;
  uint32_t capabilities = 0;                 // kCap*
  std::optional<uint16_t> protocol_version;  // absent in the 49-byte form

  // The name up to its first \0.
  std::string NameText() const;
  // `text` cut to 32 bytes, \0-filled.
  static std::array<uint8_t, kHiNameSize> MakeName(std::string_view text);
  bool operator==(const HiResponse&) const = default;
};

// ERRATA 1.5: bit (n-1) of moving_bits is motor n.
struct MotorStatusResponse {
  static constexpr MsgType kType = MsgType::kMotorStatus;
  uint32_t moving_bits = 0;
  uint8_t dmx_adjusting = 0;
  bool operator==(const MotorStatusResponse&) const = default;
};

struct MotorMoveResponse {
  static constexpr MsgType kType = MsgType::kMotorMove;
  uint8_t moving = 0;  // 1 = motor moving
  bool operator==(const MotorMoveResponse&) const = default;
};

// MSG_MOTOR_GET_POSITION response and unsolicited update: MOVE TIME, then one
// position per motor (N from the length).
struct MotorPositionReport {
  static constexpr MsgType kType = MsgType::kMotorGetPosition;
  uint32_t move_time_x1000 = 0;          // thousandths of a frame
  std::vector<int32_t> positions_steps;  // REQUIRES: 0..258 entries
  bool operator==(const MotorPositionReport&) const = default;
};

// ERRATA 1.6: response and unsolicited message on input change.
struct GioInReport {
  static constexpr MsgType kType = MsgType::kGioIn;
  uint32_t triggers = 0;
  bool operator==(const GioInReport&) const = default;
};

// REASON, then MOTOR only when REASON is 1 or 2. A MOTOR byte after another
// reason is accepted and kept (read leniently).
struct MotorHardStop {
  static constexpr MsgType kType = MsgType::kMotorHardStop;
  uint8_t reason = 0;            // HardStopReason
  std::optional<uint8_t> motor;  // REQUIRES: present when HardStopHasMotor(reason)
  bool operator==(const MotorHardStop&) const = default;
};

struct RtEnd {
  static constexpr MsgType kType = MsgType::kRtEnd;
  bool operator==(const RtEnd&) const = default;
};

// Aim fields of the VIRT_GET_POSITION response (only with the aim point).
struct VirtAim {
  uint8_t enabled = 0;
  int32_t x_x1000 = 0;
  int32_t y_x1000 = 0;
  int32_t z_x1000 = 0;
  bool operator==(const VirtAim&) const = default;
};

// MSG_VIRT_GET_POSITION response: 24 bytes, or 37 with the aim fields.
struct VirtPositionReport {
  static constexpr MsgType kType = MsgType::kVirtGetPosition;
  int32_t track_x100000 = 0;
  int32_t ew_x100000 = 0;
  int32_t ns_x100000 = 0;
  int32_t pan_x100000 = 0;
  int32_t tilt_x100000 = 0;
  int32_t roll_x100000 = 0;
  std::optional<VirtAim> aim;
  bool operator==(const VirtPositionReport&) const = default;
};

using DeviceMessage =
    std::variant<Ack, HiResponse, MotorStatusResponse, MotorMoveResponse, MotorPositionReport,
                 GioInReport, MotorHardStop, RtEnd, VirtPositionReport, VirtAimPoint, Unknown>;

// --- Codec ---------------------------------------------------------------------------------

// What decoding does with data bytes after the last field of a message's
// layout (and after the last whole entry of a list, or the last optional field
// that is there whole).
enum class TrailingBytes : uint8_t {
  // A kTrailing (or kTruncated) DecodeError: the exact reading, for tools that
  // judge what a peer sent and for round trips.
  kReject,
  // Ignored, as a receiver does: the protocol grows by appending fields
  // ("Document Revision History": PROTOCOL VERSION at the end of HI, the
  // STOP_ALL flags, RUN_MOVE FLAGS and camera angles, optional SHOOT_FRAME
  // parameters), so a device reads the fields it knows and skips what a newer
  // host appends. Data shorter than the layout is still a DecodeError. Lists
  // take whole entries only (UPLOAD_MOVE_AXIS positions, trigger pairs, blur
  // motors, positions); an optional field cut short counts as absent; of
  // VIRT_CONFIG type 1 the longest of its four forms that fits is read. ACKs
  // are always exact (2 or 4 bytes).
  kIgnore,
};

// What decoding a request does with a field its data lacks or holds only part of.
enum class MissingFields : uint8_t {
  // A kTruncated DecodeError (the spec's layouts; ERR_GENERAL by SuggestedAck).
  kError,
  // The field reads as 0, and so does every field after it (the rest of the
  // data is consumed): a list then has no entries, an optional field is
  // absent, a "one or more" list may be empty. This is how Dragonframe's
  // reference firmware reads its requests (docs/devices/dmc16.md
  // "length_checks").
  kZero,
};

// Decodes a frame sent by Dragonframe. A type with kFlagAck is an Ack (2 or 4
// data bytes), whatever the acknowledged type; a type with no request layout
// is Unknown. A known layout with the wrong data length is a DecodeError
// (kTruncated / kTrailing, offset into the data section); see TrailingBytes
// and MissingFields. Encoding is always exact: what is decoded with kIgnore
// re-encodes without the ignored bytes.
Result<HostMessage> DecodeHostMessage(const Frame& frame,
                                      TrailingBytes trailing = TrailingBytes::kReject);
Result<HostMessage> DecodeHostMessage(uint16_t type, ByteView data,
                                      TrailingBytes trailing = TrailingBytes::kReject,
                                      MissingFields missing = MissingFields::kError);

// Decodes a frame sent by a device; same rules with the response layouts.
Result<DeviceMessage> DecodeDeviceMessage(const Frame& frame,
                                          TrailingBytes trailing = TrailingBytes::kReject);
Result<DeviceMessage> DecodeDeviceMessage(uint16_t type, ByteView data,
                                          TrailingBytes trailing = TrailingBytes::kReject);

// The Type on the wire (kFlagAck included for an Ack).
uint16_t TypeOf(const HostMessage& m);
uint16_t TypeOf(const DeviceMessage& m);

// Appends one complete frame carrying `m` with ID `id` to `out`.
// REQUIRES: the struct's REQUIRES hold (then the data fits kMaxDataLength).
void Encode(uint32_t id, const HostMessage& m, Bytes& out);
void Encode(uint32_t id, const DeviceMessage& m, Bytes& out);
Bytes Encode(uint32_t id, const HostMessage& m);
Bytes Encode(uint32_t id, const DeviceMessage& m);

// Appends only the data section of `m`.
void EncodeData(const HostMessage& m, Bytes& out);
void EncodeData(const DeviceMessage& m, Bytes& out);

// One line for transcripts, e.g. "MOTOR_MOVE motor=3 position=-1200"
// (dmc_describe.cpp).
std::string Describe(const HostMessage& m);
std::string Describe(const DeviceMessage& m);

// The ACK code a device should answer a request that failed to decode with:
// a layout whose length does not fit (kTruncated, kTrailing, kBadLength) is
// ERR_GENERAL (a malformed message, no single parameter out of range); a bad
// field value is ERR_RANGE; kBadChecksum is ERR_CHECKSUM; kUnknown is
// ERR_UNSUPPORTED.
AckCode SuggestedAck(const DecodeError& e);

}  // namespace moco::dmc

#endif  // MOCO_WIRE_DMC_H_
