// Tests of the DMC v2 message layouts (dmc-v2-protocol.txt "Message Types",
// every MSG_* section; ERRATA dmc 1.3-1.11; FACTS "DMC v2"): golden frames from
// fixtures/wire/dmc.json, round trips of every message in both directions, and
// the decode errors of wrong lengths.
#include "wire/dmc.h"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

namespace moco::dmc {

namespace spec_oracle {
// The spec's checksum routine, compiled in dmc_frame_test.cpp.
uint16_t computeChecksum(const uint8_t* data, int bytes);
}  // namespace spec_oracle

// Counterexamples print as their one-line description.
inline void showValue(const HostMessage& m, std::ostream& os) { os << Describe(m); }
inline void showValue(const DeviceMessage& m, std::ostream& os) { os << Describe(m); }

namespace {

using Kind = DecodeError::Kind;
using wire::FromHex;
using wire::ToHex;

// --- Golden vectors ---------------------------------------------------------------

struct Vector {
  std::string name;
  std::string direction;
  Bytes bytes;
  std::string describe;
};

std::vector<Vector> LoadVectors() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string path = std::string(root != nullptr ? root : ".") + "/fixtures/wire/dmc.json";
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  if (!in.good()) return {};
  const nlohmann::json doc = nlohmann::json::parse(in);
  EXPECT_EQ(doc.at("protocol"), "dmc");
  std::vector<Vector> out;
  for (const auto& v : doc.at("vectors")) {
    auto bytes = FromHex(v.at("hex").get<std::string>());
    EXPECT_TRUE(bytes.has_value()) << v.at("name");
    out.push_back({v.at("name"), v.at("direction"), bytes.value_or(Bytes{}), v.at("describe")});
    EXPECT_FALSE(v.at("meaning").get<std::string>().empty());
    EXPECT_FALSE(v.at("spec").get<std::string>().empty());
  }
  return out;
}

TEST(DmcGoldenTest, EveryVectorDecodesDescribesAndReencodes) {
  const auto vectors = LoadVectors();
  ASSERT_FALSE(vectors.empty());
  for (const Vector& v : vectors) {
    SCOPED_TRACE(v.name);
    ASSERT_TRUE(v.direction == "host" || v.direction == "device");
    // The spec's own routine: a valid frame sums to zero.
    EXPECT_EQ(spec_oracle::computeChecksum(v.bytes.data(), static_cast<int>(v.bytes.size())), 0);
    const auto frame = DecodeFrame(v.bytes);
    ASSERT_TRUE(frame.ok()) << wire::Describe(frame.error());
    if (v.direction == "host") {
      const auto m = DecodeHostMessage(*frame);
      ASSERT_TRUE(m.ok()) << wire::Describe(m.error());
      EXPECT_EQ(Describe(*m), v.describe);
      EXPECT_EQ(TypeOf(*m), frame->type);
      EXPECT_EQ(ToHex(Encode(frame->id, *m)), ToHex(v.bytes));
    } else {
      const auto m = DecodeDeviceMessage(*frame);
      ASSERT_TRUE(m.ok()) << wire::Describe(m.error());
      EXPECT_EQ(Describe(*m), v.describe);
      EXPECT_EQ(TypeOf(*m), frame->type);
      EXPECT_EQ(ToHex(Encode(frame->id, *m)), ToHex(v.bytes));
    }
  }
}

TEST(DmcGoldenTest, VectorsCoverEveryAlternativeAndAckCode) {
  std::set<size_t> host_alts, device_alts;
  std::set<uint16_t> host_types, device_types;
  std::set<uint32_t> codes;
  for (const Vector& v : LoadVectors()) {
    const auto frame = DecodeFrame(v.bytes);
    ASSERT_TRUE(frame.ok());
    if (v.direction == "host") {
      const auto m = DecodeHostMessage(*frame);
      ASSERT_TRUE(m.ok());
      host_alts.insert(m->index());
      host_types.insert(frame->type);
    } else {
      const auto m = DecodeDeviceMessage(*frame);
      ASSERT_TRUE(m.ok());
      device_alts.insert(m->index());
      device_types.insert(frame->type);
      if (const auto* a = std::get_if<Ack>(&*m)) codes.insert(a->code);
    }
  }
  EXPECT_EQ(host_alts.size(), std::variant_size_v<HostMessage>);
  EXPECT_EQ(device_alts.size(), std::variant_size_v<DeviceMessage>);
  for (AckCode c :
       {AckCode::kOk, AckCode::kErrChecksum, AckCode::kErrMoving, AckCode::kErrUnsupported,
        AckCode::kErrRange, AckCode::kErrGeneral, AckCode::kErrNotInPosition, AckCode::kErrPreroll,
        AckCode::kErrPostroll, AckCode::kErrAimPoint, AckCode::kErrSoftUp, AckCode::kErrSoftLow,
        AckCode::kErrHardUp, AckCode::kErrHardLow}) {
    EXPECT_TRUE(codes.count(ToWire(c))) << AckCodeName(ToWire(c));
  }
  // Every request type from the host, every device layout from the device.
  for (uint16_t t = 0; t < 0x0400; ++t) {
    if (!IsKnownType(t)) continue;
    const bool device_only = t == ToWire(MsgType::kMotorHardStop) || t == ToWire(MsgType::kRtEnd);
    if (!device_only) {
      EXPECT_TRUE(host_types.count(t)) << TypeName(t);
    }
  }
  for (MsgType t : {MsgType::kHi, MsgType::kMotorStatus, MsgType::kMotorMove,
                    MsgType::kMotorGetPosition, MsgType::kGioIn, MsgType::kMotorHardStop,
                    MsgType::kRtEnd, MsgType::kVirtGetPosition, MsgType::kVirtAimPoint}) {
    EXPECT_TRUE(device_types.count(ToWire(t))) << TypeName(ToWire(t));
  }
}

// --- Names ----------------------------------------------------------------------------

TEST(DmcNamesTest, TypeAndCodeNamesFollowTheSpec) {
  EXPECT_EQ(TypeName(0x0001), "HI");
  EXPECT_EQ(TypeName(0x0115), "RT_SHOOT_FRAME2");
  EXPECT_EQ(TypeName(0x0206), "VIRT_JOG_ON_LINE");
  EXPECT_EQ(TypeName(0x8031), "ACK MOTOR_MOVE");
  EXPECT_EQ(TypeName(0x0204), "0x0204");
  EXPECT_EQ(TypeName(0x8400), "ACK 0x0400");
  EXPECT_EQ(AckCodeName(0x0010), "OK");
  EXPECT_EQ(AckCodeName(0x0016), "ERR_NOT_IN_POSITION");
  EXPECT_EQ(AckCodeName(0x0019), "ERR_AIM_POINT");
  EXPECT_EQ(AckCodeName(0x0023), "ERR_HARD_LOW");
  EXPECT_EQ(AckCodeName(0x0024), "0x0024");
  EXPECT_EQ(AckCodeName(0x00010010), "0x00010010");
  EXPECT_EQ(HardStopReasonName(100), "ENGINE_EXCEPTION");
  EXPECT_EQ(HardStopReasonName(7), "7");
  EXPECT_FALSE(IsKnownType(kLegacyVirtJogOnLineType));
  EXPECT_EQ(kMaxDataLength, 1036u);
}

// --- Decode errors ------------------------------------------------------------------

struct BadCase {
  const char* what;
  bool host;
  uint16_t type;
  size_t length;
  Kind kind;
  size_t offset;
  uint8_t first = 0;  // the first data byte (VIRT_CONFIG TYPE)
};

TEST(DmcDecodeErrorTest, WrongLengthsGiveTypedErrorsWithOffsets) {
  const BadCase cases[] = {
      {"MOTOR_MOVE missing a POSITION byte", true, 0x0031, 4, Kind::kTruncated, 1},
      {"MOTOR_MOVE with a trailing byte", true, 0x0031, 6, Kind::kTrailing, 5},
      {"MOTOR_STOP empty", true, 0x0032, 0, Kind::kTruncated, 0},
      {"HI request with data", true, 0x0001, 1, Kind::kTrailing, 0},
      {"GIO_IN request with data (ERRATA 1.6)", true, 0x0022, 4, Kind::kTrailing, 0},
      {"MOTOR_STOP_ALL with 2 flag bytes", true, 0x0033, 2, Kind::kTruncated, 0},
      {"MOTOR_STOP_ALL with 5 bytes", true, 0x0033, 5, Kind::kTrailing, 4},
      {"DMX without a value", true, 0x0020, 3, Kind::kTruncated, 3},
      {"MOTOR_SET_LIMITS short", true, 0x0039, 11, Kind::kTruncated, 11},
      {"RT_UPLOAD_MOVE_AXIS without a position", true, 0x0101, 5, Kind::kTruncated, 5},
      {"RT_UPLOAD_MOVE_AXIS with a partial position", true, 0x0101, 11, Kind::kTruncated, 9},
      {"RT_UPLOAD_MOVE_DMX without a level", true, 0x0102, 6, Kind::kTruncated, 6},
      {"RT_UPLOAD_MOVE_TRIGGERS half a pair", true, 0x0104, 8, Kind::kTruncated, 8},
      {"RT_RUN_MOVE one byte of FLAGS", true, 0x0111, 30, Kind::kTruncated, 29},
      {"RT_RUN_MOVE short of BLOOP TIME", true, 0x0111, 28, Kind::kTruncated, 27},
      {"RT_RUN_MOVE past CAMERA CLOSE ANGLE", true, 0x0111, 36, Kind::kTrailing, 35},
      {"RT_SHOOT_FRAME partial motor triple", true, 0x0112, 15, Kind::kTruncated, 12},
      {"RT_SHOOT_FRAME2 short header", true, 0x0115, 11, Kind::kTruncated, 10},
      {"RT_JOG_ALL short", true, 0x0120, 7, Kind::kTruncated, 4},
      {"VIRT_CONFIG empty", true, 0x0200, 0, Kind::kTruncated, 0},
      {"VIRT_CONFIG none with data", true, 0x0200, 2, Kind::kTrailing, 1, 0},
      {"VIRT_CONFIG boom-swing-track short", true, 0x0200, 92, Kind::kTruncated, 89, 1},
      {"VIRT_CONFIG boom-swing-track odd tail", true, 0x0200, 100, Kind::kBadLength, 93, 1},
      {"VIRT_CONFIG boom-swing-track table short", true, 0x0200, 576, Kind::kBadLength, 93, 1},
      {"VIRT_CONFIG swing-pan long", true, 0x0200, 18, Kind::kTrailing, 17, 2},
      {"VIRT_CONFIG swing-pan short", true, 0x0200, 16, Kind::kTruncated, 13, 2},
      {"VIRT_JOG_ON_LINE short", true, 0x0206, 2, Kind::kTruncated, 1},
      {"VIRT_AIM_POINT short", true, 0x0207, 12, Kind::kTruncated, 9},
      {"ACK with 1 byte", true, 0x8001, 1, Kind::kTruncated, 0},
      {"ACK with 3 bytes", false, 0x8031, 3, Kind::kBadLength, 0},
      {"ACK with 5 bytes", false, 0x8031, 5, Kind::kTrailing, 4},
      {"ACK with no code", false, 0x8031, 0, Kind::kTruncated, 0},
      {"HI response of 50 bytes", false, 0x0001, 50, Kind::kTruncated, 49},
      {"HI response of 48 bytes", false, 0x0001, 48, Kind::kTruncated, 45},
      {"HI response of 52 bytes", false, 0x0001, 52, Kind::kTrailing, 51},
      {"MOTOR_STATUS response short", false, 0x0030, 4, Kind::kTruncated, 4},
      {"MOTOR_MOVE response long", false, 0x0031, 2, Kind::kTrailing, 1},
      {"MOTOR_GET_POSITION partial position", false, 0x0034, 6, Kind::kTruncated, 4},
      {"MOTOR_GET_POSITION without MOVE TIME", false, 0x0034, 0, Kind::kTruncated, 0},
      {"GIO_IN response empty (ERRATA 1.6)", false, 0x0022, 0, Kind::kTruncated, 0},
      {"RT_END with data", false, 0x0114, 1, Kind::kTrailing, 0},
      {"VIRT_GET_POSITION partial aim", false, 0x0205, 25, Kind::kTruncated, 25},
      {"VIRT_GET_POSITION short", false, 0x0205, 23, Kind::kTruncated, 20},
      {"VIRT_GET_POSITION past the aim", false, 0x0205, 38, Kind::kTrailing, 37},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.what);
    Bytes data(c.length, 0);
    if (!data.empty()) data[0] = c.first;
    const DecodeError e = c.host ? DecodeHostMessage(c.type, data).error()
                                 : DecodeDeviceMessage(c.type, data).error();
    EXPECT_EQ(e.kind, c.kind) << wire::Describe(e);
    EXPECT_EQ(e.offset, c.offset) << wire::Describe(e);
    EXPECT_EQ(SuggestedAck(e), AckCode::kErrGeneral);
  }
}

TEST(DmcDecodeErrorTest, HardStopMotorByteFollowsTheReason) {
  // Reasons 1 and 2 need the MOTOR byte.
  const auto missing = DecodeDeviceMessage(0x003a, Bytes{1});
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().kind, Kind::kTruncated);
  EXPECT_EQ(missing.error().offset, 1u);
  // Reason 0 with a MOTOR byte anyway: read leniently and kept, so it re-encodes.
  const auto extra = DecodeDeviceMessage(0x003a, Bytes{0, 4});
  ASSERT_TRUE(extra.ok());
  EXPECT_EQ(std::get<MotorHardStop>(*extra), (MotorHardStop{0, 4}));
  const auto too_long = DecodeDeviceMessage(0x003a, Bytes{2, 4, 0});
  ASSERT_FALSE(too_long.ok());
  EXPECT_EQ(too_long.error().kind, Kind::kTrailing);
  EXPECT_EQ(too_long.error().offset, 2u);
}

TEST(DmcDecodeErrorTest, SuggestedAckCodes) {
  EXPECT_EQ(SuggestedAck({Kind::kTruncated, 0, ""}), AckCode::kErrGeneral);
  EXPECT_EQ(SuggestedAck({Kind::kTrailing, 0, ""}), AckCode::kErrGeneral);
  EXPECT_EQ(SuggestedAck({Kind::kBadLength, 0, ""}), AckCode::kErrGeneral);
  EXPECT_EQ(SuggestedAck({Kind::kBadValue, 0, ""}), AckCode::kErrRange);
  EXPECT_EQ(SuggestedAck({Kind::kBadChecksum, 0, ""}), AckCode::kErrChecksum);
  EXPECT_EQ(SuggestedAck({Kind::kUnknown, 0, ""}), AckCode::kErrUnsupported);
}

TEST(DmcDecodeTest, AckDecodesForAnyAcknowledgedType) {
  // ERRATA 1.4: Type | 0x8000, u16 code. The acknowledged type need not be known.
  const auto a = DecodeDeviceMessage(0x8400, Bytes{0x13, 0x00});
  ASSERT_TRUE(a.ok());
  EXPECT_EQ(std::get<Ack>(*a), (Ack{0x0400, 0x0013, AckWidth::k16}));
  // FACTS: the 32-bit form; the low two bytes are the code.
  const auto w = DecodeHostMessage(0x8034, Bytes{0x10, 0x00, 0x00, 0x00});
  ASSERT_TRUE(w.ok());
  EXPECT_EQ(std::get<Ack>(*w), (Ack{0x0034, 0x0010, AckWidth::k32}));
}

TEST(DmcDecodeTest, UploadStartIndexSplitsTheLastSetFlag) {
  // START INDEX 0x80000005: index 5, the last set for this channel.
  const auto m = DecodeHostMessage(0x0101, Bytes{3, 0x05, 0x00, 0x00, 0x80, 0x10, 0, 0, 0});
  ASSERT_TRUE(m.ok());
  const auto& axis = std::get<RtUploadMoveAxis>(*m);
  EXPECT_EQ(axis.motor, 3);
  EXPECT_EQ(axis.start_index, 5u);
  EXPECT_TRUE(axis.last_set);
  EXPECT_EQ(axis.positions_steps, std::vector<int32_t>{16});
}

TEST(DmcDecodeTest, RequestOnlyTypesFromADeviceAreUnknown) {
  const auto m = DecodeDeviceMessage(0x0036, Bytes{1, 2});
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(std::get<Unknown>(*m), (Unknown{0x0036, {1, 2}}));
}

TEST(DmcDescribeTest, HiNameIsCutAtNulAndEscaped) {
  HiResponse hi;
  hi.name = HiResponse::MakeName("A\"b\xc3\xa9");
  hi.protocol_version = 2;
  EXPECT_EQ(hi.NameText(), "A\"b\xc3\xa9");
  const std::string d = Describe(DeviceMessage{hi});
  EXPECT_NE(d.find("name=\"A\\x22b\\xc3\\xa9\""), std::string::npos) << d;
  EXPECT_EQ(HiResponse::MakeName(std::string(40, 'x'))[31], 'x');
}

// --- Generators -------------------------------------------------------------------------

template <class T>
rc::Gen<T> Any() {
  return rc::gen::arbitrary<T>();
}

template <class T>
rc::Gen<std::optional<T>> Opt(rc::Gen<T> g) {
  return rc::gen::oneOf(rc::gen::just(std::optional<T>()),
                        rc::gen::map(std::move(g), [](T v) { return std::optional<T>(v); }));
}

template <class T>
rc::Gen<std::optional<T>> Opt() {
  return Opt(rc::gen::arbitrary<T>());
}

// Types with a device-side layout (dmc-v2-protocol.txt "Response Data").
bool DeviceHasLayout(uint16_t t) {
  for (MsgType m : {MsgType::kHi, MsgType::kMotorStatus, MsgType::kMotorMove,
                    MsgType::kMotorGetPosition, MsgType::kGioIn, MsgType::kMotorHardStop,
                    MsgType::kRtEnd, MsgType::kVirtGetPosition, MsgType::kVirtAimPoint}) {
    if (ToWire(m) == t) return true;
  }
  return false;
}

template <class T>
rc::Gen<std::vector<T>> VecOf(size_t lo, size_t hi, rc::Gen<T> g) {
  return rc::gen::mapcat(rc::gen::inRange<size_t>(lo, hi + 1),
                         [g](size_t n) { return rc::gen::container<std::vector<T>>(n, g); });
}

rc::Gen<uint32_t> StartIndex() { return rc::gen::inRange<uint32_t>(0, kStartIndexMask + 1); }

rc::Gen<BlurMotor> GenBlurMotor() {
  return rc::gen::build<BlurMotor>(rc::gen::set(&BlurMotor::motor),
                                   rc::gen::set(&BlurMotor::pos_a_steps),
                                   rc::gen::set(&BlurMotor::pos_b_steps));
}

rc::Gen<Ack> GenAck() {
  return rc::gen::oneOf(
      rc::gen::build<Ack>(rc::gen::set(&Ack::type, rc::gen::inRange<uint16_t>(0, 0x8000)),
                          rc::gen::set(&Ack::code, rc::gen::inRange<uint32_t>(0, 0x10000)),
                          rc::gen::set(&Ack::width, rc::gen::just(AckWidth::k16))),
      rc::gen::build<Ack>(rc::gen::set(&Ack::type, rc::gen::inRange<uint16_t>(0, 0x8000)),
                          rc::gen::set(&Ack::code),
                          rc::gen::set(&Ack::width, rc::gen::just(AckWidth::k32))));
}

// A type that has no layout in the given direction (and no ACK flag).
rc::Gen<Unknown> GenUnknown(bool host) {
  return rc::gen::build<Unknown>(
      rc::gen::set(&Unknown::type, rc::gen::suchThat(rc::gen::inRange<uint16_t>(0, 0x8000),
                                                     [host](uint16_t t) {
                                                       if (host) {
                                                         return !IsKnownType(t) || t == 0x003a ||
                                                                t == 0x0114;
                                                       }
                                                       return !DeviceHasLayout(t);
                                                     })),
      rc::gen::set(&Unknown::data, VecOf<uint8_t>(0, kMaxDataLength, Any<uint8_t>())));
}

rc::Gen<VirtAimPoint> GenAimPoint() {
  return rc::gen::build<VirtAimPoint>(
      rc::gen::set(&VirtAimPoint::enable), rc::gen::set(&VirtAimPoint::x_x1000),
      rc::gen::set(&VirtAimPoint::y_x1000), rc::gen::set(&VirtAimPoint::z_x1000));
}

rc::Gen<RtRunMove> GenRunMove() {
  return rc::gen::mapcat(rc::gen::inRange(0, 4), [](int optional_fields) {
    return rc::gen::build<RtRunMove>(
        rc::gen::set(&RtRunMove::fps_x1000), rc::gen::set(&RtRunMove::start_frame),
        rc::gen::set(&RtRunMove::end_frame), rc::gen::set(&RtRunMove::preroll_ms),
        rc::gen::set(&RtRunMove::postroll_ms), rc::gen::set(&RtRunMove::sync_dmx),
        rc::gen::set(&RtRunMove::bloop_outputs), rc::gen::set(&RtRunMove::bloop_dmx_channel),
        rc::gen::set(&RtRunMove::bloop_time_ms),
        rc::gen::set(&RtRunMove::flags,
                     optional_fields >= 1
                         ? rc::gen::map(Any<uint16_t>(),
                                        [](uint16_t v) { return std::optional<uint16_t>(v); })
                         : rc::gen::just(std::optional<uint16_t>())),
        rc::gen::set(&RtRunMove::camera_open_angle_deg,
                     optional_fields >= 2
                         ? rc::gen::map(rc::gen::inRange<uint16_t>(0, 361),
                                        [](uint16_t v) { return std::optional<uint16_t>(v); })
                         : rc::gen::just(std::optional<uint16_t>())),
        rc::gen::set(&RtRunMove::camera_close_angle_deg,
                     optional_fields >= 3
                         ? rc::gen::map(rc::gen::inRange<uint16_t>(0, 361),
                                        [](uint16_t v) { return std::optional<uint16_t>(v); })
                         : rc::gen::just(std::optional<uint16_t>())));
  });
}

rc::Gen<VirtAxisSetup> GenAxisSetup() {
  return rc::gen::build<VirtAxisSetup>(rc::gen::set(&VirtAxisSetup::motor),
                                       rc::gen::set(&VirtAxisSetup::steps_per_unit),
                                       rc::gen::set(&VirtAxisSetup::position_x100000));
}

rc::Gen<VirtAxisScale> GenAxisScale() {
  return rc::gen::build<VirtAxisScale>(rc::gen::set(&VirtAxisScale::motor),
                                       rc::gen::set(&VirtAxisScale::steps_per_unit));
}

rc::Gen<VirtConfig> GenVirtConfig() {
  using Rig = decltype(VirtConfig::rig);
  auto bst = rc::gen::build<VirtRigBoomSwingTrack>(
      rc::gen::set(&VirtRigBoomSwingTrack::boom, GenAxisSetup()),
      rc::gen::set(&VirtRigBoomSwingTrack::swing, GenAxisSetup()),
      rc::gen::set(&VirtRigBoomSwingTrack::track, GenAxisSetup()),
      rc::gen::set(&VirtRigBoomSwingTrack::pan, GenAxisSetup()),
      rc::gen::set(&VirtRigBoomSwingTrack::tilt, GenAxisSetup()),
      rc::gen::set(&VirtRigBoomSwingTrack::roll, GenAxisSetup()),
      rc::gen::set(&VirtRigBoomSwingTrack::boom_length_x1000),
      rc::gen::set(&VirtRigBoomSwingTrack::boom_ext_x1000),
      rc::gen::set(&VirtRigBoomSwingTrack::nodal_x_x1000),
      rc::gen::set(&VirtRigBoomSwingTrack::nodal_y_x1000),
      rc::gen::set(&VirtRigBoomSwingTrack::nodal_z_x1000),
      rc::gen::set(&VirtRigBoomSwingTrack::compensation,
                   Opt<std::array<int32_t, kBoomCompensationEntries>>()),
      rc::gen::set(&VirtRigBoomSwingTrack::safe_distance_x1000, Opt<int32_t>()));
  auto swing_pan =
      rc::gen::build<VirtRigSwingPan>(rc::gen::set(&VirtRigSwingPan::swing, GenAxisScale()),
                                      rc::gen::set(&VirtRigSwingPan::pan, GenAxisScale()));
  auto raw = rc::gen::build<VirtRigRaw>(
      rc::gen::set(&VirtRigRaw::type,
                   rc::gen::suchThat(Any<uint8_t>(), [](uint8_t t) { return t > 2; })),
      rc::gen::set(&VirtRigRaw::data, VecOf<uint8_t>(0, kMaxDataLength - 1, Any<uint8_t>())));
  auto rig =
      rc::gen::oneOf(rc::gen::just(Rig{VirtRigNone{}}),
                     rc::gen::map(bst, [](VirtRigBoomSwingTrack r) { return Rig{std::move(r)}; }),
                     rc::gen::map(swing_pan, [](VirtRigSwingPan r) { return Rig{r}; }),
                     rc::gen::map(raw, [](VirtRigRaw r) { return Rig{std::move(r)}; }));
  return rc::gen::map(rig, [](Rig r) { return VirtConfig{std::move(r)}; });
}

template <class Variant, class T>
rc::Gen<Variant> As(rc::Gen<T> g) {
  return rc::gen::map(std::move(g), [](T v) { return Variant{std::move(v)}; });
}

template <class Variant, class T>
rc::Gen<Variant> Empty() {
  return rc::gen::just(Variant{T{}});
}

// One generator per HostMessage alternative, in variant order.
std::vector<rc::Gen<HostMessage>> HostGens() {
  using H = HostMessage;
  return {
      As<H>(GenAck()),
      Empty<H, HiRequest>(),
      As<H>(rc::gen::build<Dmx>(
          rc::gen::set(&Dmx::ramp), rc::gen::set(&Dmx::start_channel),
          rc::gen::set(&Dmx::values, VecOf<uint8_t>(1, kMaxDataLength - 3, Any<uint8_t>())))),
      As<H>(rc::gen::build<GioOut>(rc::gen::set(&GioOut::triggers))),
      Empty<H, GioInRequest>(),
      As<H>(rc::gen::build<GioCam>(rc::gen::set(&GioCam::flags))),
      Empty<H, MotorStatusRequest>(),
      As<H>(rc::gen::build<MotorMove>(rc::gen::set(&MotorMove::motor),
                                      rc::gen::set(&MotorMove::position_steps))),
      As<H>(rc::gen::build<MotorStop>(rc::gen::set(&MotorStop::motor))),
      As<H>(rc::gen::build<MotorStopAll>(rc::gen::set(&MotorStopAll::flags, Opt<uint32_t>()))),
      Empty<H, MotorGetPositionRequest>(),
      As<H>(rc::gen::build<MotorResetPosition>(rc::gen::set(&MotorResetPosition::motor),
                                               rc::gen::set(&MotorResetPosition::position_steps))),
      As<H>(rc::gen::build<MotorJog>(rc::gen::set(&MotorJog::motor), rc::gen::set(&MotorJog::speed),
                                     rc::gen::set(&MotorJog::destination_steps))),
      As<H>(rc::gen::build<MotorConfigure>(rc::gen::set(&MotorConfigure::motor),
                                           rc::gen::set(&MotorConfigure::flags))),
      As<H>(rc::gen::build<MotorSetSpeed>(rc::gen::set(&MotorSetSpeed::motor),
                                          rc::gen::set(&MotorSetSpeed::max_velocity_steps_per_s),
                                          rc::gen::set(&MotorSetSpeed::max_accel_steps_per_s2))),
      As<H>(rc::gen::build<MotorSetLimits>(
          rc::gen::set(&MotorSetLimits::motor), rc::gen::set(&MotorSetLimits::lower_enable),
          rc::gen::set(&MotorSetLimits::lower_limit_steps),
          rc::gen::set(&MotorSetLimits::upper_enable),
          rc::gen::set(&MotorSetLimits::upper_limit_steps), rc::gen::set(&MotorSetLimits::hw_set))),
      As<H>(rc::gen::build<RtUploadMoveBegin>(rc::gen::set(&RtUploadMoveBegin::start_frame),
                                              rc::gen::set(&RtUploadMoveBegin::end_frame))),
      As<H>(rc::gen::build<RtUploadMoveAxis>(
          rc::gen::set(&RtUploadMoveAxis::motor),
          rc::gen::set(&RtUploadMoveAxis::start_index, StartIndex()),
          rc::gen::set(&RtUploadMoveAxis::last_set),
          rc::gen::set(&RtUploadMoveAxis::positions_steps,
                       VecOf<int32_t>(1, (kMaxDataLength - 5) / 4, Any<int32_t>())))),
      As<H>(rc::gen::build<RtUploadMoveDmx>(
          rc::gen::set(&RtUploadMoveDmx::channel),
          rc::gen::set(&RtUploadMoveDmx::start_index, StartIndex()),
          rc::gen::set(&RtUploadMoveDmx::last_set),
          rc::gen::set(&RtUploadMoveDmx::levels,
                       VecOf<uint8_t>(1, kMaxDataLength - 6, Any<uint8_t>())))),
      As<H>(rc::gen::build<RtUploadMoveTriggers>(
          rc::gen::set(&RtUploadMoveTriggers::mask),
          rc::gen::set(&RtUploadMoveTriggers::points,
                       VecOf<TriggerPoint>(
                           0, (kMaxDataLength - 4) / 8,
                           rc::gen::build<TriggerPoint>(rc::gen::set(&TriggerPoint::frame_index),
                                                        rc::gen::set(&TriggerPoint::values)))))),
      Empty<H, RtUploadMoveEnd>(),
      As<H>(rc::gen::build<RtPositionFrame>(rc::gen::set(&RtPositionFrame::frame))),
      As<H>(GenRunMove()),
      As<H>(rc::gen::build<RtShootFrame>(
          rc::gen::set(&RtShootFrame::frame), rc::gen::set(&RtShootFrame::direction),
          rc::gen::set(&RtShootFrame::exposure_ms), rc::gen::set(&RtShootFrame::blur_percent_x10),
          rc::gen::set(&RtShootFrame::motors,
                       VecOf<BlurMotor>(0, (kMaxDataLength - 11) / 9, GenBlurMotor())))),
      As<H>(rc::gen::build<RtShootFrame2>(
          rc::gen::set(&RtShootFrame2::frame), rc::gen::set(&RtShootFrame2::exposure_ms),
          rc::gen::set(&RtShootFrame2::open_angle_deg),
          rc::gen::set(&RtShootFrame2::close_angle_deg),
          rc::gen::set(&RtShootFrame2::motors,
                       VecOf<BlurMotor>(0, (kMaxDataLength - 12) / 9, GenBlurMotor())))),
      Empty<H, RtGo>(),
      Empty<H, RtStopLoop>(),
      As<H>(rc::gen::build<RtJogAll>(rc::gen::set(&RtJogAll::fps_x1000),
                                     rc::gen::set(&RtJogAll::destination_frame))),
      As<H>(GenVirtConfig()),
      As<H>(rc::gen::build<VirtMove>(rc::gen::set(&VirtMove::axis),
                                     rc::gen::set(&VirtMove::position_x100000))),
      As<H>(rc::gen::build<VirtStop>(rc::gen::set(&VirtStop::axis))),
      As<H>(rc::gen::build<VirtJog>(rc::gen::set(&VirtJog::axis), rc::gen::set(&VirtJog::speed),
                                    rc::gen::set(&VirtJog::destination_x100000))),
      As<H>(rc::gen::build<VirtJogOnLine>(rc::gen::set(&VirtJogOnLine::axis),
                                          rc::gen::set(&VirtJogOnLine::speed))),
      Empty<H, VirtGetPositionRequest>(),
      As<H>(GenAimPoint()),
      As<H>(GenUnknown(/*host=*/true)),
  };
}

rc::Gen<HiResponse> GenHi() {
  return rc::gen::build<HiResponse>(
      rc::gen::set(&HiResponse::name), rc::gen::set(&HiResponse::fw_major),
      rc::gen::set(&HiResponse::fw_minor), rc::gen::set(&HiResponse::fw_rev),
      rc::gen::set(&HiResponse::motor_count), rc::gen::set(&HiResponse::dmx_count),
      rc::gen::set(&HiResponse::gio_out_count), rc::gen::set(&HiResponse::gio_in_count),
      rc::gen::set(&HiResponse::hw_limit_count), rc::gen::set(&HiResponse::upload_frame_count),
      rc::gen::set(&HiResponse::capabilities),
      rc::gen::set(&HiResponse::protocol_version, Opt<uint16_t>()));
}

rc::Gen<MotorHardStop> GenHardStop() {
  return rc::gen::mapcat(Any<uint8_t>(), [](uint8_t reason) {
    auto motor =
        HardStopHasMotor(reason)
            ? rc::gen::map(Any<uint8_t>(), [](uint8_t m) { return std::optional<uint8_t>(m); })
            : Opt<uint8_t>();
    return rc::gen::map(motor, [reason](std::optional<uint8_t> m) {
      return MotorHardStop{reason, m};
    });
  });
}

// One generator per DeviceMessage alternative, in variant order.
std::vector<rc::Gen<DeviceMessage>> DeviceGens() {
  using D = DeviceMessage;
  return {
      As<D>(GenAck()),
      As<D>(GenHi()),
      As<D>(rc::gen::build<MotorStatusResponse>(rc::gen::set(&MotorStatusResponse::moving_bits),
                                                rc::gen::set(&MotorStatusResponse::dmx_adjusting))),
      As<D>(rc::gen::build<MotorMoveResponse>(rc::gen::set(&MotorMoveResponse::moving))),
      As<D>(rc::gen::build<MotorPositionReport>(
          rc::gen::set(&MotorPositionReport::move_time_x1000),
          rc::gen::set(&MotorPositionReport::positions_steps,
                       VecOf<int32_t>(0, (kMaxDataLength - 4) / 4, Any<int32_t>())))),
      As<D>(rc::gen::build<GioInReport>(rc::gen::set(&GioInReport::triggers))),
      As<D>(GenHardStop()),
      Empty<D, RtEnd>(),
      As<D>(rc::gen::build<VirtPositionReport>(
          rc::gen::set(&VirtPositionReport::track_x100000),
          rc::gen::set(&VirtPositionReport::ew_x100000),
          rc::gen::set(&VirtPositionReport::ns_x100000),
          rc::gen::set(&VirtPositionReport::pan_x100000),
          rc::gen::set(&VirtPositionReport::tilt_x100000),
          rc::gen::set(&VirtPositionReport::roll_x100000),
          rc::gen::set(&VirtPositionReport::aim,
                       Opt(rc::gen::build<VirtAim>(
                           rc::gen::set(&VirtAim::enabled), rc::gen::set(&VirtAim::x_x1000),
                           rc::gen::set(&VirtAim::y_x1000), rc::gen::set(&VirtAim::z_x1000)))))),
      As<D>(GenAimPoint()),
      As<D>(GenUnknown(/*host=*/false)),
  };
}

// --- Round trips ---------------------------------------------------------------------------

template <class Variant, class DecodeFn>
void CheckRoundTrip(const char* direction, const std::vector<rc::Gen<Variant>>& gens,
                    DecodeFn decode) {
  ASSERT_EQ(gens.size(), std::variant_size_v<Variant>);
  for (size_t i = 0; i < gens.size(); ++i) {
    const auto gen = gens[i];
    const std::string name = std::string(direction) + " alternative " + std::to_string(i);
    const bool ok = rc::check(name, [gen, i, decode] {
      const Variant m = *gen;
      RC_ASSERT(m.index() == i);
      const auto id = *rc::gen::arbitrary<uint32_t>();
      const Bytes bytes = Encode(id, m);
      RC_ASSERT(bytes.size() <= kMaxFrameSize);
      const auto frame = DecodeFrame(bytes);
      RC_ASSERT(frame.ok());
      RC_ASSERT(frame->id == id);
      RC_ASSERT(frame->type == TypeOf(m));
      const auto back = decode(*frame);
      RC_ASSERT(back.ok());
      RC_ASSERT(*back == m);
      RC_ASSERT(Describe(*back) == Describe(m));
    });
    EXPECT_TRUE(ok) << name;
  }
}

TEST(DmcRoundTripTest, EveryHostMessageAlternative) {
  CheckRoundTrip<HostMessage>("host", HostGens(),
                              [](const Frame& f) { return DecodeHostMessage(f); });
}

TEST(DmcRoundTripTest, EveryDeviceMessageAlternative) {
  CheckRoundTrip<DeviceMessage>("device", DeviceGens(),
                                [](const Frame& f) { return DecodeDeviceMessage(f); });
}

// Decoding is faithful: whatever decodes re-encodes to the same data bytes, in
// both directions, for any type and any data.
RC_GTEST_PROP(DmcDecodeProp, AnythingDecodedReencodesToTheSameData, ()) {
  const auto type =
      *rc::gen::oneOf(rc::gen::arbitrary<uint16_t>(),
                      rc::gen::elementOf(std::vector<uint16_t>{
                          0x0001, 0x0020, 0x0033, 0x0034, 0x003a, 0x0101, 0x0102, 0x0104, 0x0111,
                          0x0112, 0x0115, 0x0200, 0x0205, 0x8031, 0x8001}));
  const auto data =
      *rc::gen::oneOf(VecOf<uint8_t>(0, 64, Any<uint8_t>()),
                      rc::gen::map(VecOf<uint8_t>(0, 600, Any<uint8_t>()), [](Bytes b) {
                        if (!b.empty())
                          b[0] = static_cast<uint8_t>(b[0] % 4);  // VIRT_CONFIG types 0..3
                        return b;
                      }));
  const auto host = DecodeHostMessage(type, data);
  if (host.ok()) {
    Bytes again;
    EncodeData(*host, again);
    RC_ASSERT(again == data);
    RC_ASSERT(TypeOf(*host) == type);
  }
  const auto device = DecodeDeviceMessage(type, data);
  if (device.ok()) {
    Bytes again;
    EncodeData(*device, again);
    RC_ASSERT(again == data);
    RC_ASSERT(TypeOf(*device) == type);
  }
}

// --- Missing fields (MissingFields::kZero) ------------------------------------------------
// As Dragonframe's reference firmware reads a request: a field the data lacks,
// or holds only part of, reads 0, and so does every field after it.

TEST(DmcMissingFieldsTest, AFieldCutShortAndAllAfterItReadZero) {
  const auto zero = [](MsgType t, const Bytes& data) {
    return DecodeHostMessage(ToWire(t), data, TrailingBytes::kIgnore, MissingFields::kZero);
  };
  const auto g = zero(MsgType::kGioOut, Bytes{1, 0});
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(std::get<GioOut>(g.value()).triggers, 0u) << "its two bytes are not used";
  const auto s = zero(MsgType::kMotorSetSpeed, Bytes{2, 0xd0, 0x07, 0, 0, 9});
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(std::get<MotorSetSpeed>(s.value()), (MotorSetSpeed{2, 2000, 0}));
  const auto j = zero(MsgType::kMotorJog, Bytes{3, 0x10});
  ASSERT_TRUE(j.ok());
  EXPECT_EQ(std::get<MotorJog>(j.value()), (MotorJog{3, 0, 0}));
  const auto stop = zero(MsgType::kMotorStop, Bytes{});
  ASSERT_TRUE(stop.ok());
  EXPECT_EQ(std::get<MotorStop>(stop.value()).motor, 0);
  // A "one or more" list may be empty; whole fields and trailing bytes read as ever.
  const auto axis = zero(MsgType::kRtUploadMoveAxis, Bytes{1, 0, 0, 0, 0, 7});
  ASSERT_TRUE(axis.ok());
  EXPECT_TRUE(std::get<RtUploadMoveAxis>(axis.value()).positions_steps.empty());
  const auto move = zero(MsgType::kMotorMove, Bytes{1, 5, 0, 0, 0, 9});
  ASSERT_TRUE(move.ok());
  EXPECT_EQ(std::get<MotorMove>(move.value()), (MotorMove{1, 5}));
  // The default is the spec's: shorter data is an error.
  EXPECT_EQ(
      DecodeHostMessage(ToWire(MsgType::kGioOut), Bytes{1, 0}, TrailingBytes::kIgnore).error().kind,
      Kind::kTruncated);
}

// --- Trailing bytes ---------------------------------------------------------------------
// The protocol grows by appending fields ("Document Revision History": PROTOCOL
// VERSION at the end of HI, STOP_ALL Flags, RUN_MOVE FLAGS and camera angles,
// SHOOT_FRAME's optional parameters), so a receiver reads the layout it knows
// and ignores what follows (TrailingBytes::kIgnore); the exact reading stays
// the default.

Bytes WithTail(const HostMessage& m, size_t extra) {
  Bytes data;
  EncodeData(m, data);
  for (size_t i = 0; i < extra; ++i) data.push_back(static_cast<uint8_t>(0xa5 + i));
  return data;
}

TEST(DmcTrailingTest, BytesAfterTheKnownLayoutOfEveryRequestFamilyAreIgnored) {
  VirtRigBoomSwingTrack bst;
  bst.boom.motor = 3;
  VirtRigBoomSwingTrack bst_sd = bst;
  bst_sd.safe_distance_x1000 = 2500;
  VirtRigBoomSwingTrack bst_table = bst;
  bst_table.compensation.emplace();
  (*bst_table.compensation)[7] = 42;
  VirtRigBoomSwingTrack bst_both = bst_table;
  bst_both.safe_distance_x1000 = 2500;
  RtRunMove run_full;
  run_full.fps_x1000 = 24000;
  run_full.flags = kPlayLoop;
  run_full.camera_open_angle_deg = 90;
  run_full.camera_close_angle_deg = 270;
  struct Case {
    const char* family;
    HostMessage m;
    size_t extra;
  };
  const Case cases[] = {
      // No data in the layout.
      {"HI", HiRequest{}, 2},
      {"GIO_IN (ERRATA 1.6)", GioInRequest{}, 4},
      {"MOTOR_STATUS", MotorStatusRequest{}, 1},
      {"MOTOR_GET_POSITION", MotorGetPositionRequest{}, 3},
      {"RT_UPLOAD_MOVE_END", RtUploadMoveEnd{}, 1},
      {"RT_GO", RtGo{}, 2},
      {"RT_STOP_LOOP", RtStopLoop{}, 1},
      {"VIRT_GET_POSITION", VirtGetPositionRequest{}, 5},
      // Fixed layouts.
      {"GIO_OUT", GioOut{5}, 1},
      {"GIO_CAM", GioCam{kGioCamShutter}, 3},
      {"MOTOR_MOVE", MotorMove{3, -1200}, 1},
      {"MOTOR_STOP", MotorStop{2}, 4},
      {"MOTOR_RESET_POSITION", MotorResetPosition{1, 77}, 1},
      {"MOTOR_JOG", MotorJog{1, 500, 9000}, 2},
      {"MOTOR_CONFIGURE", MotorConfigure{1, kMotorEnabled}, 1},
      {"MOTOR_SET_SPEED", MotorSetSpeed{1, 3000, 6000}, 3},
      {"MOTOR_SET_LIMITS", MotorSetLimits{1, 1, -10, 1, 10, 2}, 1},
      {"RT_UPLOAD_MOVE_BEGIN", RtUploadMoveBegin{0, 10}, 1},
      {"RT_POSITION_FRAME", RtPositionFrame{4}, 1},
      {"RT_JOG_ALL", RtJogAll{24000, 3}, 1},
      {"VIRT_MOVE", VirtMove{1, 100}, 1},
      {"VIRT_STOP", VirtStop{2}, 1},
      {"VIRT_JOG", VirtJog{1, 10000, 5}, 1},
      {"VIRT_JOG_ON_LINE (ERRATA 1.10)", VirtJogOnLine{2, -300}, 1},
      {"VIRT_AIM_POINT", VirtAimPoint{1, 1, 2, 3}, 1},
      {"VIRT_CONFIG none", VirtConfig{VirtRigNone{}}, 3},
      {"VIRT_CONFIG swing-pan", VirtConfig{VirtRigSwingPan{{1, 100}, {2, 200}}}, 1},
      // Optional fields in their longest form (ERRATA 1.7).
      {"MOTOR_STOP_ALL with Flags", MotorStopAll{kStopAllSilent}, 2},
      {"RT_RUN_MOVE with FLAGS and both angles", run_full, 4},
      {"VIRT_CONFIG boom-swing-track, 93 bytes", VirtConfig{bst}, 3},
      {"VIRT_CONFIG boom-swing-track + SAFE DISTANCE", VirtConfig{bst_sd}, 3},
      {"VIRT_CONFIG boom-swing-track + table", VirtConfig{bst_table}, 3},
      {"VIRT_CONFIG boom-swing-track + both", VirtConfig{bst_both}, 9},
      // Lists: a partial entry after the whole ones.
      {"RT_UPLOAD_MOVE_AXIS", RtUploadMoveAxis{1, 0, true, {5, -6}}, 3},
      {"RT_UPLOAD_MOVE_TRIGGERS", RtUploadMoveTriggers{0x3, {{1, 2}}}, 7},
      {"RT_SHOOT_FRAME", RtShootFrame{2, 1, 500, 500, {{1, 10, 20}}}, 8},
      {"RT_SHOOT_FRAME2", RtShootFrame2{2, 500, 90, 270, {{1, 10, 20}}}, 8},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.family);
    const uint16_t type = TypeOf(c.m);
    const Bytes data = WithTail(c.m, c.extra);
    // The exact reading refuses it (kTrailing, or kTruncated / kBadLength
    // where the tail starts another entry or form).
    EXPECT_FALSE(DecodeHostMessage(type, data).ok());
    const auto lenient = DecodeHostMessage(type, data, TrailingBytes::kIgnore);
    ASSERT_TRUE(lenient.ok()) << wire::Describe(lenient.error());
    EXPECT_EQ(*lenient, c.m) << Describe(*lenient);
  }
}

TEST(DmcTrailingTest, AnOptionalFieldCutShortIsAbsentAndItsBytesIgnored) {
  // MSG_MOTOR_STOP_ALL "Flags DWORD (Optional)": 2 bytes are no Flags.
  const auto stop = DecodeHostMessage(0x0033, Bytes{1, 0}, TrailingBytes::kIgnore);
  ASSERT_TRUE(stop.ok());
  EXPECT_EQ(std::get<MotorStopAll>(*stop).flags, std::nullopt);
  // RT_RUN_MOVE: 30 bytes are the 29-byte form; 34 bytes FLAGS + OPEN ANGLE.
  RtRunMove run;
  run.fps_x1000 = 24000;
  const auto thirty = DecodeHostMessage(0x0111, WithTail(run, 1), TrailingBytes::kIgnore);
  ASSERT_TRUE(thirty.ok());
  EXPECT_EQ(std::get<RtRunMove>(*thirty), run);
  const auto open_only = DecodeHostMessage(0x0111, WithTail(run, 5), TrailingBytes::kIgnore);
  ASSERT_TRUE(open_only.ok());
  EXPECT_TRUE(std::get<RtRunMove>(*open_only).flags.has_value());
  EXPECT_TRUE(std::get<RtRunMove>(*open_only).camera_open_angle_deg.has_value());
  EXPECT_FALSE(std::get<RtRunMove>(*open_only).camera_close_angle_deg.has_value());
  // VIRT_CONFIG type 1: the longest of 93/97/577/581 that fits is read.
  VirtRigBoomSwingTrack bst;
  const auto hundred =
      DecodeHostMessage(0x0200, WithTail(VirtConfig{bst}, 7), TrailingBytes::kIgnore);
  ASSERT_TRUE(hundred.ok());
  EXPECT_TRUE(std::get<VirtRigBoomSwingTrack>(std::get<VirtConfig>(*hundred).rig)
                  .safe_distance_x1000.has_value());
  // A byte list takes every byte: DMX values and upload levels have no tail.
  const Bytes dmx = WithTail(Dmx{0, 1, {10, 20}}, 2);
  EXPECT_EQ(DecodeHostMessage(0x0020, dmx, TrailingBytes::kIgnore).value(),
            DecodeHostMessage(0x0020, dmx).value());
}

TEST(DmcTrailingTest, DataShorterThanTheLayoutStaysAnError) {
  const struct {
    const char* what;
    uint16_t type;
    size_t length;
    Kind kind;
    uint8_t first = 0;
  } cases[] = {
      {"MOTOR_MOVE missing a POSITION byte", 0x0031, 4, Kind::kTruncated},
      {"MOTOR_STOP empty", 0x0032, 0, Kind::kTruncated},
      {"MOTOR_SET_LIMITS short", 0x0039, 11, Kind::kTruncated},
      {"DMX without a value", 0x0020, 3, Kind::kTruncated},
      {"RT_UPLOAD_MOVE_AXIS without a whole position", 0x0101, 8, Kind::kTruncated},
      {"RT_UPLOAD_MOVE_DMX without a level", 0x0102, 6, Kind::kTruncated},
      {"RT_UPLOAD_MOVE_TRIGGERS short of MASK", 0x0104, 3, Kind::kTruncated},
      {"RT_RUN_MOVE short of BLOOP TIME", 0x0111, 28, Kind::kTruncated},
      {"RT_SHOOT_FRAME2 short header", 0x0115, 11, Kind::kTruncated},
      {"VIRT_CONFIG empty", 0x0200, 0, Kind::kTruncated},
      {"VIRT_CONFIG boom-swing-track short", 0x0200, 92, Kind::kTruncated, 1},
      {"VIRT_CONFIG swing-pan short", 0x0200, 16, Kind::kTruncated, 2},
      {"VIRT_AIM_POINT short", 0x0207, 12, Kind::kTruncated},
      {"ACK with 3 bytes", 0x8031, 3, Kind::kBadLength},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.what);
    Bytes data(c.length, 0);
    if (!data.empty()) data[0] = c.first;
    const auto r = DecodeHostMessage(c.type, data, TrailingBytes::kIgnore);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().kind, c.kind);
    EXPECT_EQ(SuggestedAck(r.error()), AckCode::kErrGeneral);
  }
}

// Laws of kIgnore, both directions, any type and data: it decodes everything
// the exact reading decodes, to the same message; and whatever it decodes
// re-encodes to a prefix of the data (the ignored bytes are never kept, so
// encoding stays exact).
RC_GTEST_PROP(DmcDecodeProp, IgnoringTrailingBytesReadsALeadingPartOfTheData, ()) {
  const auto type =
      *rc::gen::oneOf(rc::gen::arbitrary<uint16_t>(),
                      rc::gen::elementOf(std::vector<uint16_t>{
                          0x0001, 0x0020, 0x0022, 0x0031, 0x0033, 0x0034, 0x003a, 0x0101, 0x0102,
                          0x0104, 0x0111, 0x0112, 0x0115, 0x0200, 0x0205, 0x0206, 0x8031}));
  const auto data =
      *rc::gen::oneOf(VecOf<uint8_t>(0, 64, Any<uint8_t>()),
                      rc::gen::map(VecOf<uint8_t>(0, 600, Any<uint8_t>()), [](Bytes b) {
                        if (!b.empty()) b[0] = static_cast<uint8_t>(b[0] % 4);
                        return b;
                      }));
  auto check = [&](const auto& exact, const auto& lenient) {
    if (exact.ok()) {
      RC_ASSERT(lenient.ok());
      RC_ASSERT(*lenient == *exact);
    }
    if (lenient.ok()) {
      Bytes again;
      EncodeData(*lenient, again);
      RC_ASSERT(again.size() <= data.size());
      RC_ASSERT(std::equal(again.begin(), again.end(), data.begin()));
      RC_ASSERT(TypeOf(*lenient) == type);
    }
  };
  check(DecodeHostMessage(type, data), DecodeHostMessage(type, data, TrailingBytes::kIgnore));
  check(DecodeDeviceMessage(type, data), DecodeDeviceMessage(type, data, TrailingBytes::kIgnore));
}

// ERRATA 1.7 / FACTS: each optional trailing form keeps its length.
TEST(DmcRoundTripTest, OptionalFieldFormsKeepTheirLength) {
  RtRunMove run;
  Bytes data;
  EncodeData(HostMessage{run}, data);
  EXPECT_EQ(data.size(), 29u);
  run.flags = kPlayLoop;
  data.clear();
  EncodeData(HostMessage{run}, data);
  EXPECT_EQ(data.size(), 31u);
  run.camera_open_angle_deg = 10;
  run.camera_close_angle_deg = 200;
  data.clear();
  EncodeData(HostMessage{run}, data);
  EXPECT_EQ(data.size(), 35u);

  HiResponse hi;
  data.clear();
  EncodeData(DeviceMessage{hi}, data);
  EXPECT_EQ(data.size(), kHiResponseLegacySize);
  hi.protocol_version = kProtocolVersion;
  data.clear();
  EncodeData(DeviceMessage{hi}, data);
  EXPECT_EQ(data.size(), kHiResponseSize);

  VirtRigBoomSwingTrack bst;
  data.clear();
  EncodeData(HostMessage{VirtConfig{bst}}, data);
  EXPECT_EQ(data.size(), 93u);
  bst.compensation.emplace();
  bst.safe_distance_x1000 = 1;
  data.clear();
  EncodeData(HostMessage{VirtConfig{bst}}, data);
  EXPECT_EQ(data.size(), 581u);
}

}  // namespace
}  // namespace moco::dmc
