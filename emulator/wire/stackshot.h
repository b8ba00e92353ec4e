// Codec for the Cognisys StackShot / StackShot 3X binary protocol: typed
// payloads (stackshot-protocol.txt section 2; ERRATA.md part 3).
// Pure functions only: no I/O, no clock, no logging.
//
// Layers:
//  1. Packet: the frame as bytes (sync, big-endian command id, action byte,
//     u8 length, data, checksum), with its checksum and streaming decoder:
//     wire/stackshot_frame.h (included here).
//  2. HostCommand / DeviceReply: a packet whose data is parsed into a typed
//     Payload according to the command table (FindCommand). Decode is driven
//     by the command id and action; encode is driven by the payload value.
//     The codec is stackshot.cpp, the table stackshot_table.cpp, the names
//     and descriptions stackshot_describe.cpp.
//
// Multi-byte data fields are little-endian u16/u32 and IEEE-754 f32 (ERRATA
// 3.1). f32 fields use F32, which compares bit for bit so that round trips
// of NaN and -0.0 are exact.
#ifndef MOCO_WIRE_STACKSHOT_H_
#define MOCO_WIRE_STACKSHOT_H_

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "wire/bytes.h"
#include "wire/stackshot_constants.h"
#include "wire/stackshot_frame.h"

namespace moco::stackshot {

using wire::Bytes;
using wire::ByteView;
using wire::DecodeError;
using wire::Result;

// An IEEE-754 single as carried on the wire; equality is bitwise.
class F32 {
 public:
  constexpr F32() = default;
  constexpr F32(float v) : bits_(std::bit_cast<uint32_t>(v)) {}  // NOLINT: implicit by design
  static constexpr F32 FromBits(uint32_t bits) {
    F32 f;
    f.bits_ = bits;
    return f;
  }
  constexpr float value() const { return std::bit_cast<float>(bits_); }
  constexpr uint32_t bits() const { return bits_; }
  bool operator==(const F32&) const = default;

 private:
  uint32_t bits_ = 0;
};

// ---------------------------------------------------------------------------
// Typed payloads
// ---------------------------------------------------------------------------
struct Empty {
  // Bytes a request carries beyond its empty layout and that are read past
  // (the AUTO_RETURN read's bool, as its garbled table lists), kept so the
  // packet re-encodes as it came.
  Bytes ignored;
  bool operator==(const Empty&) const = default;
};
// Read request of a units+f32 value: the tables send the units byte, the
// spec's own examples ("0x55 10 02 00 00 CK") and the DISTANCE_PER_REV table
// send none. Both are accepted and kept apart.
struct UnitsQuery {
  std::optional<Units> units;
  bool operator==(const UnitsQuery&) const = default;
};
struct U8Value {
  uint8_t value = 0;
  bool operator==(const U8Value&) const = default;
};
// bool_t: one byte; any non-zero byte reads as true (C truth), encodes as 1.
struct BoolValue {
  bool value = false;
  bool operator==(const BoolValue&) const = default;
};
struct U16Value {
  uint16_t value = 0;
  bool operator==(const U16Value&) const = default;
};
struct U32Value {
  uint32_t value = 0;
  bool operator==(const U32Value&) const = default;
};
struct F32Value {
  F32 value;
  bool operator==(const F32Value&) const = default;
};
struct UnitsF32 {
  Units units = Units::kMils;
  F32 value;
  bool operator==(const UnitsF32&) const = default;
};
// Null-terminated string. Bytes up to the first NUL form `text`; a string
// without a NUL is accepted with terminated = false. Bytes after the NUL are
// a kTrailing error. REQUIRES (encode): text holds no NUL.
struct Text {
  std::string text;
  bool terminated = true;
  bool operator==(const Text&) const = default;
};
// A one-byte enumeration. Any byte value is carried; range checks belong to
// the device (BAD_PARAM), see IsValid() below.
template <typename E>
struct EnumValue {
  E value{};
  bool operator==(const EnumValue&) const = default;
};
// CC_RAIL_MOVE, 7 bytes.
struct RailMove {
  Direction direction = Direction::kForward;
  Units units = Units::kMils;
  bool backlash = false;
  F32 distance;  // relative to the target position, in `units`
  bool operator==(const RailMove&) const = default;
};
// CC_RAIL_MOVE_AT_SPEED, 10 bytes.
struct RailMoveAtSpeed {
  Direction direction = Direction::kForward;
  Units units = Units::kMils;
  F32 distance;        // relative to the current position, in `units`
  F32 speed_fraction;  // of maximum speed, 1.0 = 100 %
  bool operator==(const RailMoveAtSpeed&) const = default;
};
// CC_RAIL_SHUTTER_FIRE, 10 bytes.
struct ShutterFire {
  uint16_t pulses = 0;
  F32 on_time_s;
  F32 off_time_s;
  bool operator==(const ShutterFire&) const = default;
};
// CC_RAIL_STACK ("subject to change"). The table says Length 48 but lists
// fields for bytes 0-43 only. Bytes 44-47 are read as one undocumented u32
// and carried verbatim; a 44-byte payload (a host that sent only the listed
// fields) is accepted with `reserved` absent.
struct RailStack {
  uint32_t mode = 0;  // setting_mode_t as u32 (comm_rail_mode_t values)
  uint32_t num_steps = 0;
  uint32_t distance = 0;
  uint32_t pano_start_steps = 0;
  uint32_t pano_stop_steps = 0;
  uint32_t x_start = 0;
  uint32_t x_end = 0;
  uint32_t y_start = 0;
  uint32_t y_end = 0;
  uint32_t z_start = 0;
  uint32_t z_end = 0;
  std::optional<uint32_t> reserved;
  bool operator==(const RailStack&) const = default;
};
// CC_RAIL_STATUS response (and CC_RAIL_STACK_STATUS, see the command table).
struct RailStatus {
  uint32_t bits = kRailStatusIdle;
  bool operator==(const RailStatus&) const = default;
};
struct NvmRead {
  uint8_t reg = 0;
  bool operator==(const NvmRead&) const = default;
};
struct NvmWrite {
  uint8_t reg = 0;
  uint32_t value = 0;
  bool operator==(const NvmWrite&) const = default;
};
struct PingRequest {
  uint8_t value = 0;
  bool operator==(const PingRequest&) const = default;
};
struct PingReply {
  uint8_t value = 0;     // request ^ 0xFF
  uint8_t reserved = 0;  // "currently set to zero"
  bool operator==(const PingReply&) const = default;
};
// CC_LOG read request. The table's text gives one U8 index but its header
// says "Length: 4"; a 4-byte request is read as a little-endian u32 index.
struct LogRequest {
  uint32_t index = 0;
  uint8_t width = 1;  // 1 or 4 bytes on the wire
  bool operator==(const LogRequest&) const = default;
};
// One Bezier control point: x is time (curve 0 starts at 0), y is position
// (mm for linear axes, degrees for rotary ones).
struct BezierPoint {
  F32 x;
  F32 y;
  bool operator==(const BezierPoint&) const = default;
};
struct BezierCurve {
  std::array<BezierPoint, kBezierPoints> p{};
  bool operator==(const BezierCurve&) const = default;
};
// CC_MOTION_CONFIG, 132 bytes (ERRATA 3.5).
struct MotionConfig {
  AxisType axis_type = AxisType::kSlider;  // u32 on the wire
  std::array<BezierCurve, kBezierCurves> curves{};
  bool operator==(const MotionConfig&) const = default;
};
// CC_MOTION_START: three bool_t (the table's "Length: 132" is a copy slip).
struct MotionStart {
  bool x = false;
  bool y = false;
  bool z = false;
  // Sent padded to the table header's Length 132 (read by its first three
  // bytes); re-encoded padded with zeros.
  bool padded = false;
  bool operator==(const MotionStart&) const = default;
};
// Data of a command whose layout the spec does not give (NAND, NOR, WIFI,
// WAD), or of an error reply; carried as is.
struct Raw {
  Bytes data;
  bool operator==(const Raw&) const = default;
};
// Data of a command id the codec does not know (a device answers
// COMM_ACTION_UNSUPPORTED_CMD).
struct Unknown {
  Bytes data;
  bool operator==(const Unknown&) const = default;
};

using Payload =
    std::variant<Empty, UnitsQuery, U8Value, BoolValue, U16Value, U32Value, F32Value, UnitsF32,
                 Text, EnumValue<Units>, EnumValue<RailMode>, EnumValue<GlobalMode>,
                 EnumValue<ShutterSetting>, EnumValue<IoMode>, EnumValue<Direction>, RailMove,
                 RailMoveAtSpeed, ShutterFire, RailStack, RailStatus, NvmRead, NvmWrite,
                 PingRequest, PingReply, LogRequest, MotionConfig, MotionStart, Raw, Unknown>;

// The data layout of one direction of one command; each value names the
// Payload alternative that carries it (kNone: the action is not allowed).
enum class Shape : uint8_t {
  kNone,
  kEmpty,
  kUnitsQuery,
  kU8,
  kBool,
  kU16,
  kU32,
  kF32,
  kUnitsF32,
  kText,
  kUnits,
  kRailMode,
  kGlobalMode,
  kShutterSetting,
  kIoMode,
  kDirection,
  kRailMove,
  kRailMoveAtSpeed,
  kShutterFire,
  kRailStack,
  kRailStatus,
  kNvmRead,
  kNvmWrite,
  kPingRequest,
  kPingReply,
  kLogRequest,
  kMotionConfig,
  kMotionStart,
  kRaw,
};

// One row of the command table. Every write is acknowledged with no data.
struct CommandInfo {
  uint16_t id;
  std::string_view name;  // "CC_RAIL_POSITION_CURRENT"
  Shape read_request;     // kNone: READ not allowed
  Shape read_response;
  Shape write_request;     // kNone: WRITE not allowed
  std::string_view field;  // name of the value in Describe ("position", "level")
  std::string_view spec;   // where the layout comes from
};

// The row for id, or nullptr for an unknown id. kPingTableId finds NOR_ACCESS.
const CommandInfo* FindCommand(uint16_t id);
std::span<const CommandInfo> AllCommands();
// "CC_RAIL_STATUS", or "UNKNOWN(0x1234)".
std::string CommandName(uint16_t id);

// A host -> device packet, typed.
struct HostCommand {
  uint16_t command = 0;
  Action action = Action::kRead;
  uint8_t axis = 0;
  bool sub_item = false;
  bool reserved_bit6 = false;
  Payload payload;
  bool operator==(const HostCommand&) const = default;
};

// What a device reply answers, as far as the decoder could tell.
enum class ReplyKind : uint8_t {
  kReadResponse,  // RSP_OK with the command's read-response layout
  kWriteAck,      // RSP_OK with no data
  kError,         // any status other than RSP_OK; data kept as Raw
  kOpaque,        // a command without a layout, or an unknown id
};

// A device -> host packet, typed.
struct DeviceReply {
  uint16_t command = 0;
  Action status = Action::kRspOk;
  uint8_t axis = 0;
  bool sub_item = false;
  bool reserved_bit6 = false;
  ReplyKind kind = ReplyKind::kWriteAck;
  Payload payload;
  bool operator==(const DeviceReply&) const = default;
};

struct DecodeOptions {
  // Take a one-byte READ of 0x110A (CC_PING's table id, NOR_ACCESS by the
  // enum) as a ping. The command id received is kept.
  bool ping_at_table_id = true;
};

// What the host asked, when known. Without it, a reply to a read/write
// command is a write ack when it carries no data and a read response when it
// does (every write in the spec is acknowledged without data).
struct ReplyContext {
  std::optional<Action> request_action;
};

// Typed decode of a host packet. Unknown ids decode to an Unknown payload
// (never an error). Errors, with offsets counted from the sync byte:
//   kBadValue at kOffsetAction: the action is not READ/WRITE, or not allowed
//     for this command (device answers UNSUPPORTED_ACTION);
//   kBadLength at kOffsetLength: the data length does not fit the layout;
//   kTrailing inside data: bytes after a string's NUL.
// (Device answers BAD_PARAM to those; see ErrorReplyStatus.)
Result<HostCommand> DecodeHostPacket(const Packet& p, const DecodeOptions& options = {});
// Typed decode of a device packet.
Result<DeviceReply> DecodeDevicePacket(const Packet& p, const ReplyContext& context = {},
                                       const DecodeOptions& options = {});
// The status a device sends for a host packet DecodeHostPacket refused.
Action ErrorReplyStatus(const DecodeError& e);

// The payload's data bytes (no header). May exceed kMaxDataBytes for an
// oversized Text/Raw; such a value cannot be sent.
Bytes EncodePayload(const Payload& payload);
// Packet for a typed message, sealed with `checksum`.
Packet ToPacket(const HostCommand& c, ChecksumAlgorithm checksum = kDefaultChecksum);
Packet ToPacket(const DeviceReply& r, ChecksumAlgorithm checksum = kDefaultChecksum);
// Appends the encoded packet to out; false (nothing appended) when the data
// would exceed kMaxDataBytes.
bool EncodeHostCommand(const HostCommand& c, Bytes& out,
                       ChecksumAlgorithm checksum = kDefaultChecksum);
bool EncodeDeviceReply(const DeviceReply& r, Bytes& out,
                       ChecksumAlgorithm checksum = kDefaultChecksum);

// The CC_PING answer to a request value.
constexpr PingReply PingAnswer(uint8_t request) {
  return PingReply{static_cast<uint8_t>(request ^ 0xFF), 0};
}

// ---------------------------------------------------------------------------
// Names and one-line descriptions (transcripts)
// ---------------------------------------------------------------------------
std::string_view ActionName(Action a);  // "read", "write", "ok", "bad-param", ...
std::string_view UnitsName(Units u);    // "mils", "mm", "steps", "deg"
std::string_view DirectionName(Direction d);
std::string_view RailModeName(RailMode m);
std::string_view GlobalModeName(GlobalMode m);
std::string_view ShutterSettingName(ShutterSetting s);
std::string_view IoModeName(IoMode m);
std::string_view AxisTypeName(AxisType t);
std::string AxisName(uint8_t axis);  // "X", "Y", "Z", "3"
// Shortest decimal text that reads back to the same float ("12.5", "-0").
std::string FormatF32(F32 v);

// Range checks the spec implies (the codec itself carries any value).
bool IsValid(Direction d);
bool IsValid(Units u);  // spec range 0-2 (kDegrees is not in the spec)
bool IsValid(GlobalMode m);
bool IsValid(ShutterSetting s);
bool IsValid(IoMode m);
bool IsValid(AxisType t);

// e.g. "CC_RAIL_POSITION_CURRENT read axis=Y units=mm".
std::string Describe(const HostCommand& c);
// e.g. "CC_RAIL_POSITION_CURRENT ok axis=X units=mm position=1.5".
std::string Describe(const DeviceReply& r);
// A packet that could not be typed: "CC_RAIL_MOVE action=5 axis=X data=0001".
std::string Describe(const Packet& p);

// ---------------------------------------------------------------------------
// CC_MOTION_CONFIG validation (the requirements listed after its table)
// ---------------------------------------------------------------------------
enum class MotionRule : uint8_t {
  kOk,
  kNotFinite,           // a coordinate of a used curve is NaN or infinite
  kCurve0StartNotZero,  // "Curve 0's starting time (P0.x) must be set to zero"
  kContinuity,          // a used curve's P0.x differs from the previous P3.x
  kTimeReversed,        // P3.x < P0.x: time must not decrease
  kP1BeforeP0,          // "P1.x must not be less than P0.x"
  kP2AfterP3,           // "P2.x must not be more than P3.x"
  kControlOutOfSpan,    // P1.x or P2.x outside [P0.x, P3.x]
  kCurveAfterEnd,       // a curve after the terminating one (P0.x == 0) is set
};
struct MotionCheck {
  MotionRule rule = MotionRule::kOk;
  int curve = -1;  // the curve that broke the rule
  bool ok() const { return rule == MotionRule::kOk; }
  bool operator==(const MotionCheck&) const = default;
};
std::string_view MotionRuleName(MotionRule rule);
// Number of curves in use: curve 0, then each following curve until the
// first whose P0.x is zero.
int UsedCurves(const MotionConfig& config);
// Checks the config; with all rules met, each used curve's time x(t) is
// non-decreasing (bounds P0.x <= P1.x, P2.x <= P3.x within [P0.x, P3.x]
// keep the cubic's derivative non-negative) and the spline is continuous in x.
MotionCheck ValidateMotionConfig(const MotionConfig& config);

}  // namespace moco::stackshot

#endif  // MOCO_WIRE_STACKSHOT_H_
