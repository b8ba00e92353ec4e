// The emulated DMC-16 against dmc-v2-protocol.txt, in virtual time: every
// message, every error reply, the unsolicited messages and real-time moves.
#include "devices/dmc16/dmc16.h"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <set>

#include "devices/dmc16/dmc16_test_support.h"

namespace moco::devices {
namespace {

using dmc::AckCode;
using sim::kNsPerMs;
using testing::Host;
using testing::Out;

constexpr std::optional<AckCode> kOk = AckCode::kOk;

Dmc16Profile SmallProfile() {
  Dmc16Profile p;
  p.motor_count = 4;
  p.hw_limit_sets = 2;
  p.gio_inputs = 4;
  p.gio_outputs = 4;
  p.dmx_channels = 16;
  p.upload_frame_count = 5000;
  p.limit_sets.push_back({1, -1000, 1000});
  return p;
}

// --- power-on, HI, framing -------------------------------------------------------------

TEST(Dmc16Hi, PowerOnAnnouncesHiWithTheProfile) {
  Host h;
  ASSERT_EQ(h.out().size(), 1u);
  const auto* hi = std::get_if<dmc::HiResponse>(&h.out()[0].msg);
  ASSERT_NE(hi, nullptr);
  EXPECT_EQ(hi->NameText(), "DMC-16");
  EXPECT_EQ(hi->motor_count, 16);
  EXPECT_EQ(hi->dmx_count, 512);
  EXPECT_EQ(hi->capabilities, 0x0783u);
  EXPECT_EQ(hi->protocol_version, std::optional<uint16_t>(2));
  EXPECT_EQ(h.out()[0].t_ns, 0);
}

TEST(Dmc16Hi, RequestIsAnsweredWithTheRequestId) {
  Host h;
  const uint32_t id = h.Send(dmc::HiRequest{});
  const Out& r = h.Reply(id);
  EXPECT_EQ(r.type, dmc::ToWire(dmc::MsgType::kHi));
  EXPECT_TRUE(std::holds_alternative<dmc::HiResponse>(r.msg));
}

TEST(Dmc16Hi, LegacyProfileSendsThe49ByteForm) {
  Dmc16Profile p;
  p.protocol_version.reset();
  Host h(p);
  const auto& hi = std::get<dmc::HiResponse>(h.out()[0].msg);
  EXPECT_FALSE(hi.protocol_version.has_value());
}

TEST(Dmc16Hi, PowerCycleAnnouncesAgainAndForgetsState) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{2, 500}), kOk);
  h.device().PowerOff();
  EXPECT_FALSE(h.device().Powered());
  const size_t before = h.out().size();
  h.Send(dmc::HiRequest{});  // ignored while off
  EXPECT_EQ(h.out().size(), before);
  h.device().PowerOn();
  ASSERT_EQ(h.out().size(), before + 1);
  EXPECT_TRUE(std::holds_alternative<dmc::HiResponse>(h.out().back().msg));
  EXPECT_EQ(h.Pos(2), 0);
}

TEST(Dmc16Framing, BadChecksumGetsErrChecksumWithTheRequestIdAndType) {
  Host h;
  wire::Bytes f = dmc::Encode(77, dmc::HostMessage{dmc::MotorStop{1}});
  f[10] ^= 0x01;  // the motor byte
  h.SendRaw(f);
  const Out& r = h.Reply(77);
  const auto* a = std::get_if<dmc::Ack>(&r.msg);
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->type, dmc::ToWire(dmc::MsgType::kMotorStop));
  EXPECT_EQ(a->code, dmc::ToWire(AckCode::kErrChecksum));
}

TEST(Dmc16Framing, DamagedHostAckIsNeverAnswered) {
  Host h;
  wire::Bytes f = dmc::Encode(5, dmc::HostMessage{dmc::Ack{0x0034, dmc::ToWire(AckCode::kOk)}});
  f[10] ^= 0x01;
  const size_t before = h.out().size();
  h.SendRaw(f);
  h.Send(dmc::Ack{0x0034, dmc::ToWire(AckCode::kOk)});
  EXPECT_EQ(h.out().size(), before);
  EXPECT_EQ(h.device().stats().host_acks, 1u);
}

TEST(Dmc16Framing, UnknownAndUnadvertisedTypesAreUnsupported) {
  Host h;
  EXPECT_EQ(h.Request(dmc::Unknown{0x0077, {}}), AckCode::kErrUnsupported);
  EXPECT_EQ(h.Request(dmc::VirtGetPositionRequest{}), AckCode::kErrUnsupported);
  EXPECT_EQ(h.Request(dmc::VirtMove{1, 100}), AckCode::kErrUnsupported);
  Dmc16Profile p;
  p.capabilities = 0;  // no real-time, no go-motion, no looping
  p.dmx_channels = 0;
  Host bare(p);
  EXPECT_EQ(bare.Request(dmc::RtUploadMoveBegin{0, 10}), AckCode::kErrUnsupported);
  EXPECT_EQ(bare.Request(dmc::RtShootFrame2{}), AckCode::kErrUnsupported);
  EXPECT_EQ(bare.Request(dmc::RtStopLoop{}), AckCode::kErrUnsupported);
  EXPECT_EQ(bare.Request(dmc::Dmx{0, 1, {5}}), AckCode::kErrUnsupported);
  EXPECT_EQ(bare.Request(dmc::RtGo{}), AckCode::kErrUnsupported);
}

TEST(Dmc16Framing, WrongLengthIsErrGeneral) {
  Host h;
  wire::Bytes f;
  dmc::EncodeFrame(9, dmc::ToWire(dmc::MsgType::kMotorMove), wire::Bytes{1, 2}, f);
  h.SendRaw(f);
  EXPECT_EQ(h.AckOf(9), AckCode::kErrGeneral);
}

TEST(Dmc16Framing, HostHardStopHaltsEverythingAndIsAcked) {
  Host h(SmallProfile());
  h.Send(dmc::MotorMove{1, 900});
  h.RunMs(200);
  EXPECT_EQ(h.Request(dmc::Unknown{dmc::ToWire(dmc::MsgType::kMotorHardStop), {}}), kOk);
  h.Settle();
  EXPECT_LT(h.Pos(1), 900);
}

// --- framing: the idle gap, checksum answers, trailing bytes ---------------------------

// `m` encoded with `extra` bytes appended to its data.
wire::Bytes WithTail(uint32_t id, const dmc::HostMessage& m, size_t extra) {
  wire::Bytes data;
  dmc::EncodeData(m, data);
  for (size_t i = 0; i < extra; ++i) data.push_back(static_cast<uint8_t>(0x5a + i));
  wire::Bytes out;
  dmc::EncodeFrame(id, dmc::TypeOf(m), data, out);
  return out;
}

// Frames of the device carrying `id`.
size_t RepliesTo(Host& h, uint32_t id) {
  size_t n = 0;
  for (const Out& o : h.out()) n += o.id == id ? 1 : 0;
  return n;
}

// A MOTOR_STATUS request whose Length byte was hit on the line: it declares
// 600 data bytes, so the device waits for 600 more.
wire::Bytes CorruptedLength(uint32_t id) {
  wire::Bytes f = dmc::Encode(id, dmc::HostMessage{dmc::MotorStatusRequest{}});
  f[dmc::kLengthOffset] = 0x58;
  f[dmc::kLengthOffset + 1] = 0x02;
  return f;
}

// Idle line (docs/protocol-notes.md): the spec has no inter-byte timeout; the
// device gives up a partial frame once the line has been idle for
// kLineIdleGapNs, so a corrupted Length holds back nothing after that.
TEST(Dmc16Framing, CorruptedLengthIsGivenUpAtTheIdleGapSoTheNextRequestIsAnsweredAtOnce) {
  Host h(SmallProfile());
  const size_t before = h.out().size();
  h.SendRaw(CorruptedLength(50));
  h.RunFor(Dmc16::kLineIdleGapNs);
  EXPECT_EQ(h.out().size(), before) << "a frame never completed is not answered";
  const sim::TimeNs sent = h.now();
  const uint32_t id = h.Send(dmc::HiRequest{});
  EXPECT_EQ(h.Reply(id).t_ns, sent);
  EXPECT_EQ(RepliesTo(h, 50), 0u);
}

TEST(Dmc16Framing, RequestsSwallowedByACorruptedLengthAreAnsweredAtTheIdleGap) {
  Host h(SmallProfile());
  h.SendRaw(CorruptedLength(50));
  h.RunMs(1);
  const uint32_t hi = h.Send(dmc::HiRequest{});
  h.RunMs(2);
  const uint32_t status = h.Send(dmc::MotorStatusRequest{});
  const sim::TimeNs last = h.now();
  // Each chunk restarts the gap; the false frame still lacks ~570 bytes.
  h.RunFor(Dmc16::kLineIdleGapNs - 1);
  EXPECT_EQ(RepliesTo(h, hi) + RepliesTo(h, status), 0u);
  h.RunMs(1);
  EXPECT_EQ(h.Reply(hi).t_ns, last + Dmc16::kLineIdleGapNs);
  EXPECT_EQ(h.Reply(status).t_ns, last + Dmc16::kLineIdleGapNs);
  EXPECT_TRUE(std::holds_alternative<dmc::HiResponse>(h.Reply(hi).msg));
  EXPECT_EQ(RepliesTo(h, 50), 0u);
}

// The gap is the line's silence, not the transport's: while the host's bytes
// wait unread (a transport behind in its reading, under load), a frame cut
// at a read's end is not given up, and completes when its rest is handed
// over.
TEST(Dmc16Framing, APartialFrameIsKeptPastTheGapWhileHostBytesWaitUnread) {
  Host h(SmallProfile());
  const wire::Bytes frame = dmc::Encode(60, dmc::HostMessage{dmc::HiRequest{}});
  const size_t cut = 5;
  h.SendRaw(wire::Bytes(frame.begin(), frame.begin() + cut));
  h.sink().host_bytes_waiting = true;
  h.RunFor(3 * Dmc16::kLineIdleGapNs);
  EXPECT_EQ(RepliesTo(h, 60), 0u);
  h.sink().host_bytes_waiting = false;
  h.SendRaw(wire::Bytes(frame.begin() + cut, frame.end()));
  h.RunMs(1);
  ASSERT_EQ(RepliesTo(h, 60), 1u);
  EXPECT_TRUE(std::holds_alternative<dmc::HiResponse>(h.Reply(60).msg));
}

// Once nothing waits, the gap runs from when the line was last seen busy.
TEST(Dmc16Framing, APartialFrameIsGivenUpAGapAfterTheWaitingBytesAreGone) {
  Host h(SmallProfile());
  h.SendRaw(CorruptedLength(50));
  h.sink().host_bytes_waiting = true;
  h.RunFor(Dmc16::kLineIdleGapNs);
  h.sink().host_bytes_waiting = false;
  h.RunFor(Dmc16::kLineIdleGapNs);
  const uint32_t id = h.Send(dmc::HiRequest{});
  EXPECT_EQ(h.Reply(id).t_ns, h.now()) << "the false frame was given up by then";
  EXPECT_EQ(RepliesTo(h, 50), 0u);
}

// "For received messages, this checksum should be zero. If it is not the
// device should respond with response code ACK_ERR_CHECKSUM": a received
// message has a header a request can have. A false "DF" in noise whose Type
// is no request's (bits outside the reference mask 0x83FF, or the ACK flag)
// is dropped silently; the resync then finds the real request.
TEST(Dmc16Framing, FalseMarkersInNoiseAreNeverAnsweredWithTheirGarbageIdAndType) {
  Host h(SmallProfile());
  const wire::Bytes text_df = {'D', 'F', 'M', 'o', 'c', 'o', '5', 'A', 4, 0, 1, 2, 3, 4, 9, 9};
  const wire::Bytes acked_df = {'D', 'F', 1, 2, 3, 4, 0x34, 0x80, 0, 0, 7, 7};
  ASSERT_FALSE(dmc::ChecksumIsZero(text_df));   // Type 0x4135, a complete candidate
  ASSERT_FALSE(dmc::ChecksumIsZero(acked_df));  // Type 0x8034
  wire::Bytes noise = {'x', 0x00};
  noise.insert(noise.end(), text_df.begin(), text_df.end());
  noise.push_back(0xff);
  noise.insert(noise.end(), acked_df.begin(), acked_df.end());
  const size_t before = h.out().size();
  h.SendRaw(noise);
  const uint32_t id = h.Send(dmc::HiRequest{});
  h.Settle();
  ASSERT_EQ(h.out().size(), before + 1) << "only the HI request is answered";
  EXPECT_EQ(h.out().back().id, id);
  EXPECT_EQ(h.device().stats().checksum_errors, 0u);
  EXPECT_GT(h.device().stats().framing_errors, 0u);
  // A damaged request of a type the device does not know is still a message:
  // ERR_CHECKSUM with its ID and Type.
  wire::Bytes unknown;
  dmc::EncodeFrame(61, 0x0077, wire::Bytes{1, 2}, unknown);
  unknown.back() ^= 0x5a;
  h.SendRaw(unknown);
  const Out& r = h.Reply(61);
  EXPECT_EQ(r.type, 0x0077 | dmc::kFlagAck);
  EXPECT_EQ(std::get<dmc::Ack>(r.msg).code, dmc::ToWire(AckCode::kErrChecksum));
}

// The protocol grows by appending fields ("Document Revision History";
// STOP_ALL Flags, RUN_MOVE FLAGS): bytes after a known layout are ignored and
// the message carried out; data shorter than the layout is ERR_GENERAL.
TEST(Dmc16Framing, BytesAfterAKnownLayoutAreIgnoredAndShorterDataIsErrGeneral) {
  Host h(SmallProfile());
  h.SendRaw(WithTail(101, dmc::MotorMove{1, 300}, 3));
  EXPECT_EQ(std::get<dmc::MotorMoveResponse>(h.Reply(101).msg).moving, 1);
  h.SendRaw(WithTail(102, dmc::HiRequest{}, 2));
  EXPECT_TRUE(std::holds_alternative<dmc::HiResponse>(h.Reply(102).msg));
  h.SendRaw(WithTail(103, dmc::MotorGetPositionRequest{}, 1));
  EXPECT_EQ(std::get<dmc::MotorPositionReport>(h.Reply(103).msg).positions_steps.size(), 4u);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 300);
  h.SendRaw(WithTail(104, dmc::MotorSetSpeed{2, 100, 200}, 1));
  EXPECT_EQ(h.AckOf(104), kOk);
  EXPECT_EQ(h.device().rig_ref().motor(2).profile().max_velocity_steps_per_s, 100);
  // STOP_ALL with 2 bytes: the optional Flags cut short count as absent.
  h.SendRaw(WithTail(105, dmc::MotorStopAll{}, 2));
  EXPECT_EQ(h.AckOf(105), kOk);
  wire::Bytes short_speed;
  dmc::EncodeFrame(106, dmc::ToWire(dmc::MsgType::kMotorSetSpeed), wire::Bytes{1, 2, 3, 4, 5},
                   short_speed);
  h.SendRaw(short_speed);
  EXPECT_EQ(h.AckOf(106), AckCode::kErrGeneral);
  wire::Bytes empty_stop;
  dmc::EncodeFrame(107, dmc::ToWire(dmc::MsgType::kMotorStop), {}, empty_stop);
  h.SendRaw(empty_stop);
  EXPECT_EQ(h.AckOf(107), AckCode::kErrGeneral);
}

// --- where the reference firmware answers otherwise (Dmc16Behaviour) --------------------
// Each switch: the spec's default, then the switched (dmc-lite) behaviour.

Dmc16Profile Switched(void (*set)(Dmc16Behaviour&)) {
  Dmc16Profile p = SmallProfile();
  set(p.behaviour);
  return p;
}

// An RT_UPLOAD_MOVE_AXIS of 499 positions: Length 2001, above the spec's 1036.
wire::Bytes BigUpload(uint32_t id) {
  dmc::RtUploadMoveAxis m{1, 0, true, std::vector<int32_t>(499, 7)};
  wire::Bytes data;
  dmc::EncodeData(m, data);
  wire::Bytes out;
  dmc::EncodeFrame(id, dmc::ToWire(dmc::MsgType::kRtUploadMoveAxis), data, out);
  return out;
}

TEST(Dmc16Behaviour, ReceiveBufferOf2048WaitsForALengthTheSpecsMinimumDrops) {
  // Spec: "at least 1048 bytes"; Length 2001 is oversize and dropped at once.
  Host spec(SmallProfile());
  ASSERT_EQ(spec.Request(dmc::RtUploadMoveBegin{0, 600}), kOk);
  spec.SendRaw(BigUpload(60));
  const uint32_t hi = spec.Send(dmc::HiRequest{});
  EXPECT_EQ(spec.Reply(hi).t_ns, spec.now());
  EXPECT_EQ(RepliesTo(spec, 60), 0u);
  // receive_buffer_bytes 2048 (dmc-lite): the header waits for its 2003 bytes.
  Host lite(Switched([](Dmc16Behaviour& b) { b.receive_buffer_bytes = 2048; }));
  ASSERT_EQ(lite.Request(dmc::RtUploadMoveBegin{0, 600}), kOk);
  const wire::Bytes big = BigUpload(60);
  lite.SendRaw(wire::Bytes(big.begin(), big.begin() + 1000));
  lite.RunMs(10);
  EXPECT_EQ(RepliesTo(lite, 60), 0u);
  lite.SendRaw(wire::Bytes(big.begin() + 1000, big.end()));
  EXPECT_EQ(lite.AckOf(60), kOk);
  EXPECT_EQ(lite.Request(dmc::RtUploadMoveEnd{}), kOk);
}

TEST(Dmc16Behaviour, WithoutRescanTheBytesBehindAFalseMarkerAreDropped) {
  // A false "DF" (Type 0x4000, no request's) whose Length 10 covers a whole
  // HI request: the candidate fails its checksum.
  wire::Bytes stream = {'D', 'F', 1, 2, 3, 4, 0x00, 0x40, 10, 0};
  const wire::Bytes real = dmc::Encode(70, dmc::HostMessage{dmc::HiRequest{}});
  stream.insert(stream.end(), real.begin(), real.end());
  ASSERT_FALSE(dmc::ChecksumIsZero(stream));
  // Spec reading: rescan from the byte after the false 'D' finds the HI.
  Host spec(SmallProfile());
  spec.SendRaw(stream);
  EXPECT_TRUE(std::holds_alternative<dmc::HiResponse>(spec.Reply(70).msg));
  // rescan_after_bad_frame false (dmc-lite): the 22 bytes are gone.
  Host lite(Switched([](Dmc16Behaviour& b) { b.rescan_after_bad_frame = false; }));
  lite.SendRaw(stream);
  lite.Settle();
  EXPECT_EQ(RepliesTo(lite, 70), 0u);
  const uint32_t next = lite.Send(dmc::MotorStatusRequest{});
  EXPECT_EQ(lite.Reply(next).t_ns, lite.now());
}

TEST(Dmc16Behaviour, MoveAnsweredWithItsResponseOrAckOk) {
  Host spec(SmallProfile());
  const uint32_t a = spec.Send(dmc::MotorMove{1, 200});
  EXPECT_EQ(std::get<dmc::MotorMoveResponse>(spec.Reply(a).msg).moving, 1);
  Host lite(Switched([](Dmc16Behaviour& b) { b.move_response = false; }));
  EXPECT_EQ(lite.Request(dmc::MotorMove{1, 200}), kOk);
  EXPECT_TRUE(lite.device().rig_ref().motor(1).IsMoving());
  lite.Settle();
  EXPECT_EQ(lite.Pos(1), 200);
  // Refusals stay refusals.
  EXPECT_EQ(lite.Request(dmc::MotorMove{9, 200}), AckCode::kErrRange);
}

TEST(Dmc16Behaviour, GetPositionAnsweredWithThePositionsOrWithAnIdZeroMessageThenAckOk) {
  Host spec(SmallProfile());
  ASSERT_EQ(spec.Request(dmc::MotorResetPosition{2, 55}), kOk);
  const uint32_t a = spec.Send(dmc::MotorGetPositionRequest{});
  EXPECT_EQ(std::get<dmc::MotorPositionReport>(spec.Reply(a).msg).positions_steps[1], 55);
  Host lite(Switched([](Dmc16Behaviour& b) { b.position_response = false; }));
  ASSERT_EQ(lite.Request(dmc::MotorResetPosition{2, 55}), kOk);
  const size_t before = lite.out().size();
  const uint32_t id = lite.Send(dmc::MotorGetPositionRequest{});
  ASSERT_EQ(lite.out().size(), before + 2);
  const Out& positions = lite.out()[before];
  EXPECT_EQ(positions.id, 0u);
  EXPECT_EQ(positions.type, dmc::ToWire(dmc::MsgType::kMotorGetPosition));
  EXPECT_EQ(std::get<dmc::MotorPositionReport>(positions.msg).positions_steps,
            (std::vector<int32_t>{0, 55, 0, 0}));
  const Out& ack = lite.out()[before + 1];
  EXPECT_EQ(ack.id, id);
  EXPECT_EQ(ack.type, dmc::ToWire(dmc::MsgType::kMotorGetPosition) | dmc::kFlagAck);
  EXPECT_EQ(std::get<dmc::Ack>(ack.msg).code, dmc::ToWire(AckCode::kOk));
}

TEST(Dmc16Behaviour, GioInRequestAnsweredWithTheInputsOrUnsupported) {
  for (const bool request : {true, false}) {
    SCOPED_TRACE(request ? "spec" : "dmc-lite");
    Dmc16Profile p = SmallProfile();
    p.behaviour.gio_in_request = request;
    Host h(p);
    h.device().gio()->SetRawInput(1, true);
    h.RunMs(50);
    // The unsolicited message on a change goes out either way.
    ASSERT_EQ(h.All<dmc::GioInReport>().size(), 1u);
    const uint32_t id = h.Send(dmc::GioInRequest{});
    if (request) {
      EXPECT_EQ(std::get<dmc::GioInReport>(h.Reply(id).msg).triggers, 0x2u);
    } else {
      EXPECT_EQ(h.AckOf(id), AckCode::kErrUnsupported);
    }
  }
}

TEST(Dmc16Behaviour, HostAckOfADeviceMessageTakenSilentlyOrAnsweredUnsupported) {
  // The host ACKs the power-on HI (device-side ID 1), as ERRATA 1.9 says.
  const dmc::HostMessage ack_of_hi = dmc::Ack{dmc::ToWire(dmc::MsgType::kHi), 0x0010};
  Host spec(SmallProfile());
  const size_t before = spec.out().size();
  spec.SendRaw(dmc::Encode(1, ack_of_hi));
  EXPECT_EQ(spec.out().size(), before);
  EXPECT_EQ(spec.device().stats().host_acks, 1u);
  Host lite(Switched([](Dmc16Behaviour& b) { b.host_acks_silent = false; }));
  lite.SendRaw(dmc::Encode(1, ack_of_hi));
  ASSERT_EQ(lite.out().size(), 2u);
  const Out& r = lite.out().back();
  EXPECT_EQ(r.id, 1u);
  EXPECT_EQ(r.type, dmc::ToWire(dmc::MsgType::kHi) | dmc::kFlagAck);
  EXPECT_EQ(std::get<dmc::Ack>(r.msg).code, dmc::ToWire(AckCode::kErrUnsupported));
  // A damaged ACK is no request either way.
  wire::Bytes damaged = dmc::Encode(1, ack_of_hi);
  damaged[10] ^= 0x01;
  lite.SendRaw(damaged);
  EXPECT_EQ(lite.out().size(), 2u);
}

TEST(Dmc16Behaviour, JogSpeedOutsideTheRangeRefusedOrTakenAtTheNearestEnd) {
  Host spec(SmallProfile());
  EXPECT_EQ(spec.Request(dmc::MotorJog{1, 0, 1000}), AckCode::kErrRange);
  EXPECT_EQ(spec.Request(dmc::MotorJog{1, 10001, 1000}), AckCode::kErrRange);
  EXPECT_FALSE(spec.device().rig_ref().motor(1).IsMoving());
  // jog_speed_checked false (dmc-lite): accepted; SPEED 0 jogs as 1 (1% of the
  // jog speed, sim::JogSpeedFraction) and 10001 or 65535 as 10000 (100%).
  auto jog_end_ns = [](uint16_t speed) {
    Host h(Switched([](Dmc16Behaviour& b) { b.jog_speed_checked = false; }));
    EXPECT_EQ(h.Request(dmc::MotorJog{1, speed, 1000}), kOk) << speed;
    h.Settle();
    EXPECT_EQ(h.Pos(1), 1000) << speed;
    return h.device().rig_ref().motor(1).CurrentPlan().EndNs();
  };
  EXPECT_EQ(jog_end_ns(0), jog_end_ns(1));
  EXPECT_EQ(jog_end_ns(10001), jog_end_ns(10000));
  EXPECT_EQ(jog_end_ns(65535), jog_end_ns(10000));
  EXPECT_GT(jog_end_ns(0), jog_end_ns(10000));
}

// fixtures/profiles/dmc-lite.json sets every answer switch as the reference
// firmware behaves (FACTS "DMC v2").
TEST(Dmc16Behaviour, DmcLiteProfileAnswersAsTheReferenceFirmware) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  Host h(LoadDmc16Profile(std::string(root != nullptr ? root : ".") +
                          "/fixtures/profiles/dmc-lite.json"));
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, dmc::kMotorEnabled}), kOk);
  EXPECT_EQ(h.Request(dmc::MotorMove{1, 100}), kOk);
  const size_t before = h.out().size();
  const uint32_t pos = h.Send(dmc::MotorGetPositionRequest{});
  EXPECT_EQ(h.out()[before].id, 0u);
  EXPECT_EQ(h.AckOf(pos), kOk);
  EXPECT_EQ(h.Request(dmc::GioInRequest{}), AckCode::kErrUnsupported);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, dmc::kMotorEnabled}), kOk);
  EXPECT_EQ(h.Request(dmc::MotorJog{2, 0, 10}), kOk);
  // The host ACKs the power-on HI (device-side ID 1).
  h.SendRaw(dmc::Encode(1, dmc::HostMessage{dmc::Ack{dmc::ToWire(dmc::MsgType::kHi), 0x0010}}));
  EXPECT_EQ(h.out().back().id, 1u);
  EXPECT_EQ(std::get<dmc::Ack>(h.out().back().msg).code, dmc::ToWire(AckCode::kErrUnsupported));
  // A Length up to its 2048-byte buffer is waited for.
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 600}), kOk);
  h.SendRaw(BigUpload(90));
  EXPECT_EQ(h.AckOf(90), kOk);
}

// --- motors -------------------------------------------------------------------------------

TEST(Dmc16Motor, MoveAnswersMovingThenReportsPositionsUntilItStops) {
  Host h(SmallProfile());
  const uint32_t id = h.Send(dmc::MotorMove{3, 4000});
  const auto* r = std::get_if<dmc::MotorMoveResponse>(&h.Reply(id).msg);
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->moving, 1);
  const uint32_t st = h.Send(dmc::MotorStatusRequest{});
  EXPECT_EQ(std::get<dmc::MotorStatusResponse>(h.Reply(st).msg).moving_bits, 0b0100u);
  h.Settle();
  EXPECT_EQ(h.Pos(3), 4000);
  const auto reports = h.All<dmc::MotorPositionReport>();
  ASSERT_GE(reports.size(), 3u);
  // About every 100 ms while moving, then one at the stop with the final position.
  for (size_t i = 1; i + 1 < reports.size(); ++i) {
    EXPECT_EQ(reports[i].first - reports[i - 1].first, 100 * kNsPerMs);
  }
  EXPECT_EQ(reports.back().second.positions_steps.size(), 4u);
  EXPECT_EQ(reports.back().second.positions_steps[2], 4000);
  const sim::TimeNs stop_ns = h.device().rig_ref().motor(3).CurrentPlan().EndNs();
  EXPECT_EQ(reports.back().first, stop_ns);
  // Nothing more once at rest.
  const size_t n = h.out().size();
  h.RunMs(1000);
  EXPECT_EQ(h.out().size(), n);
}

TEST(Dmc16Motor, MoveToCurrentPositionAnswersNotMoving) {
  Host h(SmallProfile());
  const uint32_t id = h.Send(dmc::MotorMove{1, 0});
  EXPECT_EQ(std::get<dmc::MotorMoveResponse>(h.Reply(id).msg).moving, 0);
}

TEST(Dmc16Motor, BadMotorNumbersAreErrRange) {
  Host h(SmallProfile());
  EXPECT_EQ(h.Request(dmc::MotorMove{0, 10}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorMove{5, 10}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorStop{9}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorResetPosition{0, 1}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorJog{7, 100, 5}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorConfigure{5, 1}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorSetSpeed{5, 100, 100}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorSetLimits{5, 0, 0, 0, 0, 0}), AckCode::kErrRange);
}

TEST(Dmc16Motor, GetPositionHasOnePositionPerMotor) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{4, -123}), kOk);
  const uint32_t id = h.Send(dmc::MotorGetPositionRequest{});
  const auto& r = std::get<dmc::MotorPositionReport>(h.Reply(id).msg);
  EXPECT_EQ(r.positions_steps, (std::vector<int32_t>{0, 0, 0, -123}));
}

TEST(Dmc16Motor, ResetPositionIsAckedThenConfirmedByAnUpdate) {
  Host h(SmallProfile());
  const uint32_t id = h.Send(dmc::MotorResetPosition{2, 777});
  ASSERT_EQ(h.AckOf(id), kOk);
  const auto& last = h.out().back();
  const auto* r = std::get_if<dmc::MotorPositionReport>(&last.msg);
  ASSERT_NE(r, nullptr) << "a position update follows the ACK";
  EXPECT_EQ(r->positions_steps[1], 777);
  EXPECT_LT(last.id, 0x10000u) << "the update carries a device-side ID";
  // While moving: refused.
  h.Send(dmc::MotorMove{2, 2000});
  EXPECT_EQ(h.Request(dmc::MotorResetPosition{2, 0}), AckCode::kErrMoving);
}

TEST(Dmc16Motor, SoftLimitsRefuseMovesBeyondThem) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 1, -50, 1, 80, 0}), kOk);
  EXPECT_EQ(h.Request(dmc::MotorMove{1, 81}), AckCode::kErrSoftUp);
  EXPECT_EQ(h.Request(dmc::MotorMove{1, -51}), AckCode::kErrSoftLow);
  EXPECT_EQ(h.AckOf(h.Send(dmc::MotorMove{1, 80})), std::nullopt);
  // Lower above upper, unknown enable values, unknown sets: range errors.
  EXPECT_EQ(h.Request(dmc::MotorSetLimits{1, 1, 10, 1, 5, 0}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorSetLimits{1, 2, 0, 0, 0, 0}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorSetLimits{1, 0, 0, 0, 0, 3}), AckCode::kErrRange);
}

TEST(Dmc16Motor, JogStopsAtTheSoftLimitAndChecksSpeed) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{2, 0, 0, 1, 300, 0}), kOk);
  EXPECT_EQ(h.Request(dmc::MotorJog{2, 0, 1000}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorJog{2, 10001, 1000}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::MotorJog{2, 10000, 1000}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(2), 300);
}

TEST(Dmc16Motor, InchingIsSlowerThanFullSpeedJog) {
  Host a(SmallProfile());
  Host b(SmallProfile());
  ASSERT_EQ(a.Request(dmc::MotorJog{1, 10000, 200}), kOk);
  ASSERT_EQ(b.Request(dmc::MotorJog{1, 100, 200}), kOk);
  a.RunMs(300);
  b.RunMs(300);
  EXPECT_GT(a.Pos(1), b.Pos(1));
}

TEST(Dmc16Motor, DisabledMotorRefusesToMove) {
  Host h(SmallProfile());
  // Flag bits the device has no use for (0x04, 0x08, 0x40, 0x80) are accepted.
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, dmc::kMotorBlurEnabled | 0xcc}), kOk);
  EXPECT_FALSE(h.device().rig_ref().motor(1).enabled());
  EXPECT_TRUE(h.device().rig_ref().motor(1).blur());
  EXPECT_EQ(h.Request(dmc::MotorMove{1, 10}), AckCode::kErrGeneral);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, dmc::kMotorEnabled}), kOk);
  EXPECT_EQ(h.AckOf(h.Send(dmc::MotorMove{1, 10})), std::nullopt);
}

TEST(Dmc16Motor, SetSpeedChangesTheMoveDuration) {
  Host slow(SmallProfile());
  Host fast(SmallProfile());
  EXPECT_EQ(slow.Request(dmc::MotorSetSpeed{1, 0, 100}), AckCode::kErrRange);
  EXPECT_EQ(slow.Request(dmc::MotorSetSpeed{1, 100, 0}), AckCode::kErrRange);
  ASSERT_EQ(slow.Request(dmc::MotorSetSpeed{1, 1000, 2000}), kOk);
  ASSERT_EQ(fast.Request(dmc::MotorSetSpeed{1, 8000, 16000}), kOk);
  slow.Send(dmc::MotorMove{1, 10000});
  fast.Send(dmc::MotorMove{1, 10000});
  // Trapezoid: 10000/1000 + 1000/2000 = 10.5 s versus 10000/8000 + 8000/16000 = 1.75 s.
  EXPECT_EQ(slow.device().rig_ref().motor(1).CurrentPlan().EndNs(), 10'500'000'000);
  EXPECT_EQ(fast.device().rig_ref().motor(1).CurrentPlan().EndNs(), 1'750'000'000);
}

TEST(Dmc16Motor, SecondStopAllWithinTheWindowHardStops) {
  auto stop_time = [](bool twice) {
    Host h(SmallProfile());
    h.Send(dmc::MotorMove{1, 100000});
    h.RunMs(1000);  // cruising at 5000 steps/s
    EXPECT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
    if (twice) {
      EXPECT_EQ(h.Request(dmc::MotorStopAll{dmc::kStopAllSilent}), kOk);
    }
    return h.device().rig_ref().motor(1).CurrentPlan().EndNs() - h.now();
  };
  const sim::TimeNs soft = stop_time(false);
  const sim::TimeNs hard = stop_time(true);
  EXPECT_EQ(soft, 500 * kNsPerMs);  // 5000 / 10000
  EXPECT_EQ(hard, 125 * kNsPerMs);  // 5000 / (4 * 10000)
}

TEST(Dmc16Motor, StopAllOutsideTheWindowIsAnOrdinaryStop) {
  Host h(SmallProfile());
  EXPECT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
  h.RunMs(1500);
  h.Send(dmc::MotorMove{1, 100000});
  h.RunMs(1000);
  EXPECT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
  EXPECT_EQ(h.device().rig_ref().motor(1).CurrentPlan().EndNs() - h.now(), 500 * kNsPerMs);
}

TEST(Dmc16Motor, MotorStopDecelerates) {
  Host h(SmallProfile());
  h.Send(dmc::MotorMove{2, 100000});
  h.RunMs(1000);
  ASSERT_EQ(h.Request(dmc::MotorStop{2}), kOk);
  h.Settle();
  // At 1 s: 1250 steps of ramp + 2500 of cruise; from 5000 steps/s at
  // 10000 steps/s^2 the stop takes 1250 steps more.
  EXPECT_EQ(h.Pos(2), 1250 + 2500 + 1250);
}

// --- limits and e-stop ----------------------------------------------------------------------

TEST(Dmc16Safety, LimitSwitchTripSendsHardStopWithMotorAndEnd) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{2, 0, 0, 0, 0, 1}), kOk);
  h.Send(dmc::MotorMove{2, 5000});
  h.Settle();
  EXPECT_EQ(h.Pos(2), 1000);  // the set's high switch
  const auto stops = h.All<dmc::MotorHardStop>();
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].second.reason, 1);
  EXPECT_EQ(stops[0].second.motor, std::optional<uint8_t>(2));
  EXPECT_EQ(h.Request(dmc::MotorMove{2, 1200}), AckCode::kErrHardUp);
  EXPECT_EQ(h.AckOf(h.Send(dmc::MotorMove{2, 0})), std::nullopt) << "moving away is allowed";
}

TEST(Dmc16Safety, SwappedSetGuardsTheOtherEnd) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 0, 0, 0, 0, 0x82}), kOk);
  h.device().rig()->ForceInput(2, sim::SwitchInput::kLow, true);
  // With 0x80 the LOW input guards the upper end.
  EXPECT_EQ(h.Request(dmc::MotorMove{1, 10}), AckCode::kErrHardUp);
  EXPECT_EQ(h.AckOf(h.Send(dmc::MotorMove{1, -10})), std::nullopt);
}

TEST(Dmc16Safety, EStopHaltsReportsReasonZeroAndRefusesMoves) {
  Host h(SmallProfile());
  h.Send(dmc::MotorMove{1, 3000});
  h.RunMs(300);
  h.device().rig()->EngageEStop();
  const auto stops = h.All<dmc::MotorHardStop>();
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].second.reason, 0);
  EXPECT_FALSE(stops[0].second.motor.has_value());
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
  EXPECT_EQ(h.Request(dmc::MotorMove{1, 10}), AckCode::kErrGeneral);
  h.device().rig()->ReleaseEStop();
  EXPECT_EQ(h.AckOf(h.Send(dmc::MotorMove{1, 10})), std::nullopt);
}

// --- I/O --------------------------------------------------------------------------------------

TEST(Dmc16Io, DmxImmediateRampedAndRangeChecked) {
  Host h(SmallProfile());
  EXPECT_EQ(h.Request(dmc::Dmx{0, 0, {1}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::Dmx{0, 16, {1, 2}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::Dmx{2, 1, {1}}), AckCode::kErrRange);
  ASSERT_EQ(h.Request(dmc::Dmx{0, 15, {10, 20}}), kOk);
  EXPECT_EQ(h.device().dmx().Value(15), 10);
  EXPECT_EQ(h.device().dmx().Value(16), 20);
  ASSERT_EQ(h.Request(dmc::Dmx{1, 1, {255}}), kOk);
  const uint32_t st = h.Send(dmc::MotorStatusRequest{});
  EXPECT_EQ(std::get<dmc::MotorStatusResponse>(h.Reply(st).msg).dmx_adjusting, 1);
  h.RunMs(1001);  // 255 units at 255/s
  EXPECT_EQ(h.device().dmx().Value(1), 255);
  const uint32_t st2 = h.Send(dmc::MotorStatusRequest{});
  EXPECT_EQ(std::get<dmc::MotorStatusResponse>(h.Reply(st2).msg).dmx_adjusting, 0);
}

TEST(Dmc16Io, GioOutputsInputsAndUnsolicitedChange) {
  Host h(SmallProfile());
  EXPECT_EQ(h.Request(dmc::GioOut{0x10}), AckCode::kErrRange);
  ASSERT_EQ(h.Request(dmc::GioOut{0x5}), kOk);
  EXPECT_EQ(h.device().gio_ref().outputs(), 0x5u);
  h.device().gio()->SetRawInput(1, true);
  h.RunMs(5);
  EXPECT_TRUE(h.All<dmc::GioInReport>().empty()) << "not before the debounce time";
  h.RunMs(20);
  auto reports = h.All<dmc::GioInReport>();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0].second.triggers, 0x2u);
  // A glitch shorter than the debounce is never reported.
  h.device().gio()->SetRawInput(2, true);
  h.RunMs(3);
  h.device().gio()->SetRawInput(2, false);
  h.RunMs(100);
  EXPECT_EQ(h.All<dmc::GioInReport>().size(), 1u);
  // An input beyond GIO INPUT COUNT is not visible.
  h.device().gio()->SetRawInput(9, true);
  h.RunMs(100);
  EXPECT_EQ(h.All<dmc::GioInReport>().size(), 1u);
  const uint32_t id = h.Send(dmc::GioInRequest{});
  EXPECT_EQ(std::get<dmc::GioInReport>(h.Reply(id).msg).triggers, 0x2u);
}

TEST(Dmc16Io, GioCamDrivesTheCameraLines) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::GioCam{dmc::kGioCamShutter | dmc::kGioCamMeter}), kOk);
  EXPECT_TRUE(h.device().camera().level(sim::CameraPort::kShutter));
  EXPECT_TRUE(h.device().camera().level(sim::CameraPort::kMeter));
  ASSERT_EQ(h.Request(dmc::GioCam{0}), kOk);
  EXPECT_FALSE(h.device().camera().level(sim::CameraPort::kShutter));
}

// --- uploads and real-time moves ----------------------------------------------------------------

// Uploads frames 10..10+n-1: motor 1 moves `step` per frame from 0, motor 2
// holds 50 (sent as a one-value last set), DMX channel 3 counts frames.
void UploadRamp(Host& h, uint32_t n, int32_t step, uint32_t start = 10) {
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{start, start + n - 1}), kOk);
  std::vector<int32_t> pos;
  for (uint32_t i = 0; i < n; ++i) pos.push_back(static_cast<int32_t>(i) * step);
  for (uint32_t i = 0; i < n; i += 200) {
    const uint32_t len = std::min<uint32_t>(200, n - i);
    dmc::RtUploadMoveAxis a;
    a.motor = 1;
    a.start_index = i;
    a.last_set = i + len == n;
    a.positions_steps.assign(pos.begin() + i, pos.begin() + i + len);
    ASSERT_EQ(h.Request(a), kOk);
  }
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{2, 0, true, {50}}), kOk);
  std::vector<uint8_t> levels;
  for (uint32_t i = 0; i < n; ++i) levels.push_back(static_cast<uint8_t>(i));
  ASSERT_EQ(h.Request(dmc::RtUploadMoveDmx{
                3, 0, true,
                std::vector<uint8_t>(levels.begin(), levels.begin() + std::min<uint32_t>(n, 500))}),
            kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kOk);
}

dmc::RtRunMove RunMove(uint32_t start, uint32_t end, uint32_t fps_x1000, uint32_t pre_ms,
                       uint32_t post_ms) {
  dmc::RtRunMove r;
  r.fps_x1000 = fps_x1000;
  r.start_frame = start;
  r.end_frame = end;
  r.preroll_ms = pre_ms;
  r.postroll_ms = post_ms;
  return r;
}

TEST(Dmc16Upload, RangeAndOrderErrors) {
  Host h(SmallProfile());
  EXPECT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, false, {1}}), AckCode::kErrGeneral);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveEnd{}), AckCode::kErrGeneral);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveBegin{10, 9}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 5000}), AckCode::kErrRange) << "5001 frames";
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 4999}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{100, 109}), kOk);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveAxis{5, 0, false, {1}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 8, false, {1, 2, 3}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveDmx{17, 0, false, {1}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveTriggers{1, {{10, 1}}}), AckCode::kErrRange);
  // A gap without a last set leaves frames without a position.
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, false, {1, 2, 3}}), kOk);
  EXPECT_EQ(h.Request(dmc::RtUploadMoveEnd{}), AckCode::kErrGeneral);
  EXPECT_FALSE(h.device().upload().complete());
}

TEST(Dmc16Upload, LastSetRepeatsTheFinalValueToTheEnd) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{100, 109}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, false, {5, 6}}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 2, true, {7, 8}}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kOk);
  const RtMove& u = h.device().upload();
  EXPECT_EQ(u.Position(1, 100), 5);
  EXPECT_EQ(u.Position(1, 103), 8);
  EXPECT_EQ(u.Position(1, 109), 8);
}

TEST(Dmc16Upload, PositionFrameSendsMotorsAndDmxToTheFrame) {
  Host h(SmallProfile());
  UploadRamp(h, 100, 20);
  EXPECT_EQ(h.Request(dmc::RtPositionFrame{9}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtPositionFrame{110}), AckCode::kErrRange);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{60}), kOk);
  EXPECT_EQ(h.device().dmx().Value(3), 50);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 1000);
  EXPECT_EQ(h.Pos(2), 50);
  EXPECT_EQ(h.Pos(3), 0) << "a motor without uploaded data stays";
  const auto reports = h.All<dmc::MotorPositionReport>();
  EXPECT_EQ(reports.back().second.move_time_x1000, 60000u);
}

TEST(Dmc16Upload, RunMoveWithoutUploadOrGoWithoutRunAreRefused) {
  Host h(SmallProfile());
  EXPECT_EQ(h.Request(RunMove(10, 20, 24000, 1000, 1000)), AckCode::kErrGeneral);
  EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrGeneral);
  EXPECT_EQ(h.Request(dmc::RtPositionFrame{10}), AckCode::kErrGeneral);
  UploadRamp(h, 50, 10);
  EXPECT_EQ(h.Request(RunMove(10, 10, 24000, 1000, 1000)), AckCode::kErrRange);
  EXPECT_EQ(h.Request(RunMove(10, 80, 24000, 1000, 1000)), AckCode::kErrRange);
  EXPECT_EQ(h.Request(RunMove(10, 20, 0, 1000, 1000)), AckCode::kErrRange);
}

TEST(Dmc16Run, PrerollPositionGivesFullSpeedAtTheStartFrame) {
  Host h(SmallProfile());
  UploadRamp(h, 200, 10);  // 10 steps per frame: 240 steps/s at 24 fps
  ASSERT_EQ(h.Request(RunMove(20, 150, 24000, 1000, 500)), kOk);
  h.Settle();
  // Start frame 20 is index 10: position 100; pre-roll covers v*T/2 = 120 steps.
  EXPECT_EQ(h.Pos(1), 100 - 120);
  EXPECT_EQ(h.device().ModeName(), "armed-run");
}

TEST(Dmc16Run, GoPlaysTheMoveReportingEveryFrameThenRtEnd) {
  Host h(SmallProfile());
  UploadRamp(h, 200, 10);
  ASSERT_EQ(h.Request(RunMove(20, 150, 24000, 1000, 500)), kOk);
  h.Settle();
  const size_t mark = h.out().size();
  const sim::TimeNs t_go = h.now();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  EXPECT_EQ(h.Request(dmc::MotorMove{1, 0}), AckCode::kErrMoving);
  h.Settle();
  std::vector<Out> after(h.out().begin() + static_cast<long>(mark), h.out().end());
  std::vector<std::pair<sim::TimeNs, dmc::MotorPositionReport>> frames;
  sim::TimeNs rt_end = -1;
  for (const Out& o : after) {
    // The frame reports: a whole frame's MOVE TIME within the run (the
    // periodic updates between them carry fractions of a frame).
    if (const auto* r = std::get_if<dmc::MotorPositionReport>(&o.msg)) {
      if (rt_end < 0 && r->move_time_x1000 % 1000 == 0 && r->move_time_x1000 >= 20000 &&
          r->move_time_x1000 <= 150000) {
        frames.emplace_back(o.t_ns, *r);
      }
    }
    if (std::holds_alternative<dmc::RtEnd>(o.msg)) rt_end = o.t_ns;
  }
  // Frames 20..150 inclusive, each once.
  ASSERT_EQ(frames.size(), 131u);
  for (uint32_t k = 0; k <= 130; ++k) {
    const auto& [t, r] = frames[k];
    EXPECT_EQ(r.move_time_x1000, (20 + k) * 1000) << k;
    const double ideal = static_cast<double>(t_go) + 1e9 + k * 1e9 / 24.0;
    EXPECT_GE(static_cast<double>(t), ideal - 1) << k;
    EXPECT_LT(static_cast<double>(t), ideal + 2) << k;
    // Step-accurate: on each frame the motor is on the uploaded position.
    EXPECT_EQ(r.positions_steps[0], static_cast<int32_t>((10 + k) * 10)) << k;
    EXPECT_EQ(r.positions_steps[1], 50);
  }
  ASSERT_GT(rt_end, 0);
  // Post-roll: 240 steps/s to rest in 0.5 s covers 60 steps.
  EXPECT_EQ(h.Pos(1), 1400 + 60);
  EXPECT_EQ(rt_end, frames[130].first + 500 * kNsPerMs);
  EXPECT_EQ(h.device().ModeName(), "idle");
  // The plan never held more than a window of frames.
  EXPECT_LT(h.device().rig_ref().motor(1).HeapBytes(), 16u * 1024u);
}

TEST(Dmc16Run, DmxAndTriggersFollowTheFrames) {
  Host h(SmallProfile());
  UploadRamp(h, 100, 5);
  // Reupload with triggers: redo begin to include them.
  ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{10, 109}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, true, {0}}), kOk);
  std::vector<uint8_t> lv(100);
  for (size_t i = 0; i < lv.size(); ++i) lv[i] = static_cast<uint8_t>(2 * i);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveDmx{3, 0, true, lv}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveTriggers{0x3, {{5, 0x1}, {6, 0x3}}}), kOk);
  ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kOk);
  dmc::RtRunMove r = RunMove(10, 30, 10000, 0, 0);
  r.sync_dmx = 1;
  ASSERT_EQ(h.Request(r), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  const sim::TimeNs t0 = h.now();
  h.scheduler().RunUntil(t0 + 500 * kNsPerMs + 1);  // frame 15 (index 5)
  EXPECT_EQ(h.device().dmx().Value(3), 10);
  EXPECT_EQ(h.device().gio_ref().outputs(), 0x1u);
  h.scheduler().RunUntil(t0 + 600 * kNsPerMs + 1);
  EXPECT_EQ(h.device().gio_ref().outputs(), 0x3u);
  h.scheduler().RunUntil(t0 + 700 * kNsPerMs + 1);
  EXPECT_EQ(h.device().gio_ref().outputs(), 0x0u) << "frames without an entry turn triggers off";
  EXPECT_EQ(h.device().dmx().Value(3), 14);
}

TEST(Dmc16Run, PrerollAndPostrollPastSoftLimitsAreRefused) {
  Host h(SmallProfile());
  UploadRamp(h, 200, 10);
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 1, 0, 1, 1990, 0}), kOk);
  // Start frame 10 is at 0: the pre-roll would go below 0.
  EXPECT_EQ(h.Request(RunMove(10, 100, 24000, 1000, 0)), AckCode::kErrPreroll);
  // End frame 209 is at 1990: the post-roll would pass the upper limit.
  EXPECT_EQ(h.Request(RunMove(20, 209, 24000, 0, 1000)), AckCode::kErrPostroll);
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 1, 0, 1, 500, 0}), kOk);
  EXPECT_EQ(h.Request(RunMove(20, 100, 24000, 0, 0)), AckCode::kErrSoftUp) << "path passes 500";
  EXPECT_EQ(h.Request(RunMove(20, 50, 24000, 0, 0)), kOk);
}

TEST(Dmc16Run, GoWhileMovingOrOutOfPositionIsRefused) {
  Host h(SmallProfile());
  UploadRamp(h, 200, 10);
  ASSERT_EQ(h.Request(RunMove(20, 150, 24000, 1000, 500)), kOk);
  EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrMoving) << "still going to the pre-roll";
  h.Settle();
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{1, 0}), kOk);
  EXPECT_EQ(h.Request(dmc::RtGo{}), AckCode::kErrNotInPosition);
}

TEST(Dmc16Run, StopAllDuringARunEndsItWithRtEnd) {
  Host h(SmallProfile());
  UploadRamp(h, 200, 10);
  ASSERT_EQ(h.Request(RunMove(20, 150, 24000, 1000, 500)), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  h.RunMs(2000);
  ASSERT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
  h.Settle();
  EXPECT_EQ(h.device().ModeName(), "idle");
  EXPECT_FALSE(h.device().rig_ref().AnyMoving());
}

TEST(Dmc16Run, LimitTripDuringARunSendsHardStopAndRtEnd) {
  Dmc16Profile p = SmallProfile();
  p.limit_sets = {{1, std::nullopt, 700}};
  Host h(p);
  UploadRamp(h, 200, 10);
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 0, 0, 0, 0, 1}), kOk);
  ASSERT_EQ(h.Request(RunMove(20, 150, 24000, 1000, 500)), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  h.Settle();
  ASSERT_EQ(h.All<dmc::MotorHardStop>().size(), 1u);
  EXPECT_EQ(h.All<dmc::MotorHardStop>()[0].second.reason, 1);
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
  EXPECT_EQ(h.Pos(1), 700);
}

TEST(Dmc16Run, PingPongPlaysBackAndForthUntilStopLoop) {
  Host h(SmallProfile());
  UploadRamp(h, 60, 10);
  dmc::RtRunMove r = RunMove(10, 40, 24000, 500, 500);
  r.flags = dmc::kPlayPingPong;
  ASSERT_EQ(h.Request(r), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  const size_t mark = h.out().size();
  // First pass, then the reverse pass has begun.
  h.RunMs(500 + 1250 + 500 + 2000);
  ASSERT_EQ(h.Request(dmc::RtStopLoop{}), kOk);
  h.Settle();
  std::vector<uint32_t> times;
  for (size_t i = mark; i < h.out().size(); ++i) {
    if (const auto* p = std::get_if<dmc::MotorPositionReport>(&h.out()[i].msg)) {
      times.push_back(p->move_time_x1000);
    }
  }
  // Forward 10..40, then 40 down to 10: a falling run of MOVE TIME follows a rising one.
  auto it = std::find(times.begin(), times.end(), 40000u);
  ASSERT_NE(it, times.end());
  auto down = std::find(it + 1, times.end(), 39000u);
  EXPECT_NE(down, times.end()) << "the reverse pass reports frames backwards";
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
  EXPECT_EQ(h.Pos(1), -60) << "ends past frame 10 (at 0) after the reverse post-roll";
}

TEST(Dmc16Run, CameraStillsOpenAndCloseAtTheAnglesOfEveryFrame) {
  Host h(SmallProfile());
  UploadRamp(h, 30, 10);
  dmc::RtRunMove r = RunMove(10, 14, 10000, 0, 0);
  r.flags = dmc::kPlayCameraStills;
  r.camera_open_angle_deg = 90;
  r.camera_close_angle_deg = 270;
  ASSERT_EQ(h.Request(r), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  const sim::TimeNs t0 = h.now();
  h.Settle();
  std::vector<sim::CameraPort::Edge> edges = h.device().camera().Trace();
  ASSERT_EQ(edges.size(), 10u);  // frames 10..14, open and close each
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(edges[2 * k].time_ns,
              t0 + static_cast<sim::TimeNs>(k) * 100 * kNsPerMs + 25 * kNsPerMs);
    EXPECT_TRUE(edges[2 * k].level);
    EXPECT_EQ(edges[2 * k + 1].time_ns,
              t0 + static_cast<sim::TimeNs>(k) * 100 * kNsPerMs + 75 * kNsPerMs);
    EXPECT_FALSE(edges[2 * k + 1].level);
  }
  // Camera flags without the capability are a range error.
  Dmc16Profile p = SmallProfile();
  p.capabilities &= ~dmc::kCapRtCameraTrigger;
  Host no_cam(p);
  UploadRamp(no_cam, 30, 10);
  EXPECT_EQ(no_cam.Request(r), AckCode::kErrRange);
}

TEST(Dmc16Shoot, ShootFrame2BlursBetweenTheAnglesWithTheShutterOpen) {
  Host h(SmallProfile());
  UploadRamp(h, 30, 10);
  dmc::RtShootFrame2 s;
  s.frame = 15;
  s.exposure_ms = 500;
  s.open_angle_deg = 90;
  s.close_angle_deg = 270;
  s.motors = {{1, 1000, 1400}};
  ASSERT_EQ(h.Request(s), kOk);
  h.Settle();
  // Opens at 1100, closes at 1300: 400 steps/s; ramp 400^2/(2*10000) = 8 steps.
  EXPECT_EQ(h.Pos(1), 1092);
  EXPECT_EQ(h.Pos(2), 50) << "a motor of the move that is not blurred goes to the frame";
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  const sim::TimeNs t_go = h.now();
  const sim::Plan plan = h.device().rig_ref().motor(1).CurrentPlan();
  h.Settle();
  const auto edges = h.device().camera().Trace();
  ASSERT_EQ(edges.size(), 2u);
  const sim::TimeNs open = edges[0].time_ns;
  EXPECT_EQ(open - t_go, 40 * kNsPerMs);  // 2 * 8 / 400 s
  EXPECT_EQ(edges[1].time_ns - open, 500 * kNsPerMs);
  EXPECT_NEAR(static_cast<double>(plan.StepsAt(open)), 1100, 1);
  EXPECT_NEAR(static_cast<double>(plan.StepsAt(open + 250 * kNsPerMs)), 1200, 1);
  EXPECT_NEAR(static_cast<double>(plan.StepsAt(edges[1].time_ns)), 1300, 1);
  EXPECT_EQ(h.Pos(1), 1308);
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
}

TEST(Dmc16Shoot, ShootFrameChecksItsArguments) {
  Host h(SmallProfile());
  UploadRamp(h, 30, 10);
  dmc::RtShootFrame s;
  s.frame = 15;
  s.exposure_ms = 100;
  s.blur_percent_x10 = 500;
  s.motors = {{1, 0, 100}};
  EXPECT_EQ(h.Request(dmc::RtShootFrame{99, 1, 100, 500, {}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtShootFrame{15, 1, 0, 500, {}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtShootFrame{15, 1, 100, 1001, {}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtShootFrame{15, 1, 100, 500, {{9, 0, 1}}}), AckCode::kErrRange);
  EXPECT_EQ(h.Request(dmc::RtShootFrame{15, 1, 1, 1000, {{1, 0, 100000}}}), AckCode::kErrRange)
      << "faster than the motor's max velocity";
  ASSERT_EQ(h.Request(s), kOk);
  h.Settle();
  // 50% blur centred: angles 90..270 -> 25..75, 500 steps/s, ramp 12.5 -> 12 (floor).
  EXPECT_EQ(h.Pos(1), 12);
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 88);
  EXPECT_EQ(h.device().camera().exposures(), 1u);
}

TEST(Dmc16JogAll, OnlyFromAFramePositionAndEndsOnTheDestination) {
  Host h(SmallProfile());
  UploadRamp(h, 100, 10);
  EXPECT_EQ(h.Request(dmc::RtJogAll{24000, 50}), AckCode::kErrNotInPosition);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{20}), kOk);
  EXPECT_EQ(h.Request(dmc::RtJogAll{24000, 50}), AckCode::kErrNotInPosition) << "still moving";
  h.Settle();
  EXPECT_EQ(h.Request(dmc::RtJogAll{24000, 500}), AckCode::kErrRange);
  ASSERT_EQ(h.Request(dmc::RtJogAll{24000, 50}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 400);
  EXPECT_EQ(h.device().ModeName(), "idle");
  EXPECT_TRUE(h.All<dmc::RtEnd>().empty());
  // On frame 50 now: a jog back works at once.
  ASSERT_EQ(h.Request(dmc::RtJogAll{48000, 30}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 200);
}

// --- coupling and blur (MSG_MOTOR_CONFIGURE) -------------------------------------------------

// MSG_MOTOR_GET_POSITION's answer to a request.
std::vector<int32_t> Positions(Host& h) {
  const uint32_t id = h.Send(dmc::MotorGetPositionRequest{});
  const auto* r = std::get_if<dmc::MotorPositionReport>(&h.Reply(id).msg);
  EXPECT_NE(r, nullptr) << "MOTOR_GET_POSITION answered with the positions";
  return r != nullptr ? r->positions_steps : std::vector<int32_t>{};
}

// MSG_MOTOR_MOVE taken: its response (or, where a profile answers moves so,
// an ACK OK). Returns the MOTOR STATUS byte, or 0 for the ACK.
std::optional<uint8_t> MoveTaken(Host& h, uint8_t motor, int32_t position) {
  const Out& o = h.Reply(h.Send(dmc::MotorMove{motor, position}));
  if (const auto* r = std::get_if<dmc::MotorMoveResponse>(&o.msg)) return r->moving;
  if (const auto* a = std::get_if<dmc::Ack>(&o.msg)) {
    if (static_cast<AckCode>(a->code) == AckCode::kOk) return 0;
  }
  return std::nullopt;
}

constexpr uint8_t kOn = dmc::kMotorEnabled;
constexpr uint8_t kCoupled = dmc::kMotorEnabled | dmc::kMotorCoupled;
constexpr uint8_t kCoupledReversed = dmc::kMotorEnabled | dmc::kMotorCoupledReversed;

// Capabilities 0x0100 "Couple motors"; FACTS "DMC v2": MOTOR_CONFIGURE flags
// 0x10 coupled, 0x20 coupled reversed. A coupled motor follows the motor
// before it (docs/protocol-notes.md), step for step, mirrored when reversed.
TEST(Dmc16Couple, ACoupledMotorFollowsTheMotorBeforeItThroughMovesJogsAndStops) {
  Host h(SmallProfile());
  ASSERT_TRUE(h.device().profile().Has(dmc::kCapCoupleMotors));
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupled}), kOk);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{3, kCoupledReversed}), kOk);  // follows 2, so 1
  EXPECT_EQ(h.Request(dmc::MotorConfigure{1, kCoupled}), AckCode::kErrRange)
      << "motor 1 has no motor before it";
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{3, 500}), kOk);
  EXPECT_EQ(MoveTaken(h, 1, 1000), 1);
  const uint32_t st = h.Send(dmc::MotorStatusRequest{});
  EXPECT_EQ(std::get<dmc::MotorStatusResponse>(h.Reply(st).msg).moving_bits, 0b0111u);
  h.Settle();
  EXPECT_EQ(Positions(h), (std::vector<int32_t>{1000, 1000, -500, 0}));
  ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, -200}), kOk);
  h.Settle();
  EXPECT_EQ(Positions(h), (std::vector<int32_t>{-200, -200, 700, 0}));
  // A coupled motor takes no motion of its own; stopping it stops its group.
  EXPECT_EQ(h.Request(dmc::MotorMove{2, 5}), AckCode::kErrGeneral);
  EXPECT_EQ(h.Request(dmc::MotorJog{3, 100, 5}), AckCode::kErrGeneral);
  EXPECT_EQ(MoveTaken(h, 1, 100000), 1);
  h.RunMs(1000);
  EXPECT_EQ(h.Request(dmc::MotorConfigure{2, kOn}), AckCode::kErrMoving)
      << "the coupling does not change under way";
  ASSERT_EQ(h.Request(dmc::MotorStop{3}), kOk);
  h.Settle();
  const int64_t p1 = h.Pos(1);
  EXPECT_EQ(p1, -200 + 1250 + 2500 + 1250) << "decelerated at the motor's acceleration";
  EXPECT_EQ(h.Pos(2), p1);
  EXPECT_EQ(h.Pos(3), 500 - p1);
  // One report when the group has stopped, not one per motor.
  const auto reports = h.All<dmc::MotorPositionReport>();
  ASSERT_GE(reports.size(), 2u);
  EXPECT_LT(reports[reports.size() - 2].first, reports.back().first);
  // Uncoupled, motor 2 moves alone and motor 3 now follows it.
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kOn}), kOk);
  EXPECT_EQ(MoveTaken(h, 2, static_cast<int32_t>(p1 + 10)), 1);
  h.Settle();
  EXPECT_EQ(h.Pos(1), p1);
  EXPECT_EQ(h.Pos(3), 500 - p1 - 10);
  const nlohmann::json st3 = h.device().State()["motors"][2];
  EXPECT_EQ(st3["coupled_to"], 2);
  EXPECT_EQ(st3["coupled_reversed"], true);
}

TEST(Dmc16Couple, WithoutTheCapabilityTheCouplingFlagsAreAcceptedAndIgnored) {
  Dmc16Profile p = SmallProfile();
  p.capabilities &= ~dmc::kCapCoupleMotors;
  Host h(p);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, kCoupled}), kOk);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupledReversed}), kOk);
  EXPECT_EQ(MoveTaken(h, 2, 300), 1);
  h.Settle();
  EXPECT_EQ(Positions(h), (std::vector<int32_t>{0, 300, 0, 0}));
}

// MSG_RT_POSITION_FRAME, MSG_RT_RUN_MOVE, MSG_RT_GO: a coupled motor follows
// the motor that drives it through playback instead of playing its own data.
TEST(Dmc16Couple, ACoupledMotorFollowsPlaybackInsteadOfItsOwnData) {
  Host h(SmallProfile());
  UploadRamp(h, 100, 10);  // motor 1 on a ramp, motor 2 holding 50
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupledReversed}), kOk);
  ASSERT_EQ(h.Request(dmc::RtPositionFrame{60}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 500);
  EXPECT_EQ(h.Pos(2), -500);
  ASSERT_EQ(h.Request(dmc::RtJogAll{24000, 30}), kOk) << "on a frame by the motors that play";
  h.Settle();
  EXPECT_EQ(h.Pos(2), -200);
  ASSERT_EQ(h.Request(RunMove(20, 80, 24000, 500, 500)), kOk);
  h.Settle();
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  for (int i = 0; i < 40; ++i) {
    h.RunMs(100);
    ASSERT_EQ(h.Pos(2), -h.Pos(1)) << i;
  }
  h.Settle();
  EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
  EXPECT_EQ(h.Pos(2), -h.Pos(1));
}

// MSG_MOTOR_CONFIGURE "0x02 - blur enabled"; MSG_RT_SHOOT_FRAME2 "Each motor
// provided will be part of the blur": the motors that blur are those listed
// with the blur flag; one listed without it is held on the frame's position
// (docs/protocol-notes.md). Until configured, motors are blur-enabled.
TEST(Dmc16Shoot, OnlyListedMotorsWithTheBlurFlagBlur) {
  auto shoot = [](Host& h) {
    dmc::RtShootFrame2 s;
    s.frame = 15;
    s.exposure_ms = 500;
    s.open_angle_deg = 90;
    s.close_angle_deg = 270;
    s.motors = {{1, 1000, 1400}};
    return h.Request(s);
  };
  Host h(SmallProfile());
  UploadRamp(h, 30, 10);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, kOn}), kOk);
  ASSERT_EQ(shoot(h), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 50) << "frame 15's uploaded position";
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  h.Settle();
  EXPECT_EQ(h.device().camera().exposures(), 1u);
  EXPECT_EQ(h.Pos(1), 50) << "held through the exposure";
  // With the flag it blurs; a motor coupled to it blurs with it.
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, kOn | dmc::kMotorBlurEnabled}), kOk);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupled | dmc::kMotorBlurEnabled}), kOk);
  ASSERT_EQ(shoot(h), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 1092);
  EXPECT_EQ(h.Pos(2), 1092) << "followed motor 1 from frame 15, where both stood on 50";
  ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 1308);
  EXPECT_EQ(h.Pos(2), h.Pos(1));
}

// --- the reference firmware's motion (Dmc16Behaviour; FACTS "DMC v2") ---------------------

// dmc-v2-protocol.txt MSG_MOTOR_CONFIGURE "0x01 - motor enabled". The spec
// reading: a disabled motor refuses MOVE and JOG (ERR_GENERAL) and sits out
// playback. dmc-lite (motors start disabled): it takes them and stays.
TEST(Dmc16Behaviour, DisabledMotorsIgnoreMotion) {
  for (const bool ignore : {false, true}) {
    SCOPED_TRACE(ignore ? "disabled_motors_ignore_motion" : "spec");
    Dmc16Profile p = SmallProfile();
    p.motors_enabled = false;
    p.behaviour.disabled_motors_ignore_motion = ignore;
    Host h(p);
    const std::optional<AckCode> refused =
        ignore ? kOk : std::optional<AckCode>(AckCode::kErrGeneral);
    if (ignore) {
      EXPECT_EQ(MoveTaken(h, 1, 1000), 0);
    } else {
      EXPECT_EQ(h.Request(dmc::MotorMove{1, 1000}), AckCode::kErrGeneral);
    }
    EXPECT_EQ(h.Request(dmc::MotorJog{1, 10000, 1000}), refused);
    // Listed for a blur with its blur flag set but not enabled.
    ASSERT_EQ(h.Request(dmc::MotorConfigure{1, dmc::kMotorBlurEnabled}), kOk);
    dmc::RtShootFrame2 shot{15, 100, 90, 270, {{1, 0, 100}}};
    UploadRamp(h, 30, 10);
    EXPECT_EQ(h.Request(shot), refused);
    // Uploads are taken; playback and POSITION_FRAME move no disabled motor.
    ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kOn}), kOk);
    ASSERT_EQ(h.Request(dmc::RtPositionFrame{30}), kOk);
    ASSERT_EQ(h.Request(RunMove(12, 38, 24000, 200, 200)), kOk);
    h.Settle();
    ASSERT_EQ(h.Request(dmc::RtGo{}), kOk);
    h.Settle();
    EXPECT_EQ(h.All<dmc::RtEnd>().size(), 1u);
    EXPECT_EQ(h.Pos(1), 0);
    EXPECT_EQ(h.Pos(2), 50) << "the enabled motor played";
    // Enabled, it moves.
    ASSERT_EQ(h.Request(dmc::MotorConfigure{1, kOn}), kOk);
    EXPECT_EQ(MoveTaken(h, 1, 1000), 1);
    h.Settle();
    EXPECT_EQ(h.Pos(1), 1000);
  }
}

// dmc-v2-protocol.txt ERR_SOFT_UP / ERR_SOFT_LOW, ERR_PREROLL: the spec
// reading refuses MOVE beyond a soft limit and stops JOG at it. dmc-lite:
// MOVE, JOG and POSITION_FRAME beyond complete; the limits still bound
// RUN_MOVE's pre/post-roll and the stop deceleration.
TEST(Dmc16Behaviour, SoftLimitsBoundMoves) {
  for (const bool bound : {true, false}) {
    SCOPED_TRACE(bound ? "spec" : "soft_limits_bound_moves false");
    Dmc16Profile p = SmallProfile();
    p.behaviour.soft_limits_bound_moves = bound;
    Host h(p);
    ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 1, -50, 1, 80, 0}), kOk);
    if (bound) {
      EXPECT_EQ(h.Request(dmc::MotorMove{1, 81}), AckCode::kErrSoftUp);
    } else {
      EXPECT_EQ(MoveTaken(h, 1, 81), 1);
    }
    h.Settle();
    EXPECT_EQ(h.Pos(1), bound ? 0 : 81);
    ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, -500}), kOk);
    h.Settle();
    EXPECT_EQ(h.Pos(1), bound ? -50 : -500);
    // POSITION_FRAME to frame 30 (200 steps, past the upper limit).
    UploadRamp(h, 30, 10);
    EXPECT_EQ(h.Request(dmc::RtPositionFrame{30}), bound ? AckCode::kErrSoftUp : AckCode::kOk);
    h.Settle();
    EXPECT_EQ(h.Pos(1), bound ? -50 : 200);
    // Either way the pre-roll of a run is bounded.
    ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 1, -50, 1, 1000, 0}), kOk);
    EXPECT_EQ(h.Request(RunMove(10, 30, 24000, 2000, 0)), AckCode::kErrPreroll);
  }
}

TEST(Dmc16Behaviour, SoftLimitsBoundTheStopDecelerationEvenWhenNotMoves) {
  Dmc16Profile p = SmallProfile();
  p.behaviour.soft_limits_bound_moves = false;
  Host h(p);
  ASSERT_EQ(h.Request(dmc::MotorSetLimits{1, 0, 0, 1, 4500, 0}), kOk);
  EXPECT_EQ(MoveTaken(h, 1, 100000), 1);
  h.RunMs(1000);
  ASSERT_EQ(h.Pos(1), 3750);  // 1250 of ramp + 2500 of cruise at 5000 steps/s
  // The ordinary ramp (1250 steps) would end at 5000, past the limit.
  ASSERT_EQ(h.Request(dmc::MotorStop{1}), kOk);
  h.Settle();
  EXPECT_EQ(h.Pos(1), 4500);
}

// dmc-v2-protocol.txt MSG_MOTOR_STOP_ALL. The spec reading: STOP_ALL
// decelerates and the device takes commands at once. dmc-lite: STOP_ALL
// without flags while moving sets a hard-stop state in which every request
// from MOTOR_MOVE (0x0031) up but MOTOR_GET_POSITION is refused with
// ERR_HARD_LOW, until the motors have been still for stop_all_lockout_ms.
TEST(Dmc16Behaviour, StopAllLockout) {
  for (const uint32_t lockout_ms : {0u, 2000u}) {
    SCOPED_TRACE("stop_all_lockout_ms " + std::to_string(lockout_ms));
    Dmc16Profile p = SmallProfile();
    p.behaviour.stop_all_lockout_ms = lockout_ms;
    Host h(p);
    const std::optional<AckCode> locked =
        lockout_ms != 0 ? std::optional<AckCode>(AckCode::kErrHardLow) : kOk;
    // At rest, or with the silent flag, STOP_ALL locks nothing.
    ASSERT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
    EXPECT_EQ(MoveTaken(h, 1, 100000), 1);
    h.RunMs(1000);
    ASSERT_EQ(h.Request(dmc::MotorStopAll{dmc::kStopAllSilent}), kOk);
    EXPECT_EQ(h.Request(dmc::MotorSetSpeed{1, 5000, 10000}), kOk);
    h.RunMs(2000);
    EXPECT_EQ(MoveTaken(h, 1, 100000), 1);
    h.RunMs(1000);
    ASSERT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
    const sim::TimeNs stop_ns = h.now();
    const sim::TimeNs rest_ns = h.device().rig_ref().motor(1).CurrentPlan().EndNs();
    EXPECT_EQ(rest_ns - h.now(), 500 * kNsPerMs);
    // A second STOP_ALL: refused in the hard-stop state (no hard stop then).
    EXPECT_EQ(h.Request(dmc::MotorStopAll{}), locked);
    EXPECT_EQ(h.device().rig_ref().motor(1).CurrentPlan().EndNs() - h.now(),
              (lockout_ms != 0 ? 500 : 125) * kNsPerMs);
    EXPECT_EQ(h.Request(dmc::MotorResetPosition{2, 5}), locked);
    EXPECT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 10}), locked);
    EXPECT_EQ(Positions(h).size(), 4u) << "MOTOR_GET_POSITION is always answered";
    const uint32_t st = h.Send(dmc::MotorStatusRequest{});
    EXPECT_NE(std::get_if<dmc::MotorStatusResponse>(&h.Reply(st).msg), nullptr);
    h.Settle();
    // Counted from the STOP_ALL (the motors rested 500 ms after it).
    h.scheduler().RunUntil(stop_ns + 1999 * kNsPerMs);
    if (lockout_ms != 0) {
      EXPECT_EQ(h.Request(dmc::MotorMove{1, 0}), locked) << "1999 ms after the STOP_ALL";
    } else {
      EXPECT_EQ(MoveTaken(h, 1, 0), 1);
    }
    h.RunMs(1);
    EXPECT_EQ(MoveTaken(h, 1, 0), 1);
    h.Settle();
    if (lockout_ms == 0) continue;
    // ... and never over before the motors rest: a stop of 5 s.
    ASSERT_EQ(h.Request(dmc::MotorSetSpeed{1, 5000, 1000}), kOk);
    EXPECT_EQ(MoveTaken(h, 1, 100000), 1);
    h.RunMs(6000);
    ASSERT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
    const sim::TimeNs slow_rest_ns = h.device().rig_ref().motor(1).CurrentPlan().EndNs();
    EXPECT_EQ(slow_rest_ns - h.now(), 5000 * kNsPerMs);
    h.RunMs(4999);
    EXPECT_EQ(h.Request(dmc::MotorMove{1, 0}), locked) << "still stopping";
    h.scheduler().RunUntil(slow_rest_ns);
    EXPECT_EQ(MoveTaken(h, 1, 0), 1) << "at rest, long after the STOP_ALL";
  }
}

// MSG_MOTOR_RESET_POSITION: ERR_MOVING "while the rig is moving". The spec
// reading refuses it for the motor that moves; dmc-lite checks its one moving
// flag, so any motor in motion refuses it (behaviour.
// reset_refused_while_any_moves). MSG_MOTOR_HARD_STOP from the host: taken
// as "hard stop everything" by the spec reading, ERR_UNSUPPORTED on dmc-lite,
// which only sends it (behaviour.host_hard_stop).
TEST(Dmc16Behaviour, ResetWhileAnotherMotorMovesAndTheHostsHardStop) {
  for (const bool lite : {false, true}) {
    SCOPED_TRACE(lite ? "dmc-lite" : "spec");
    Dmc16Profile p = SmallProfile();
    p.behaviour.reset_refused_while_any_moves = lite;
    p.behaviour.host_hard_stop = !lite;
    Host h(p);
    h.Send(dmc::MotorMove{2, 100000});
    h.RunMs(200);
    ASSERT_TRUE(h.device().rig_ref().motor(2).IsMoving());
    EXPECT_EQ(h.Request(dmc::MotorResetPosition{3, 50}),
              lite ? std::optional<AckCode>(AckCode::kErrMoving) : kOk);
    EXPECT_EQ(h.Request(dmc::MotorResetPosition{2, 50}), AckCode::kErrMoving);
    EXPECT_EQ(h.Request(dmc::Unknown{dmc::ToWire(dmc::MsgType::kMotorHardStop), {}}),
              lite ? std::optional<AckCode>(AckCode::kErrUnsupported) : kOk);
    // A hard stop (4 x the max acceleration) rests the motor within 100 ms.
    h.RunMs(100);
    EXPECT_EQ(h.device().rig_ref().motor(2).IsMoving(), lite);
  }
}

// dmc-lite plans a MOTOR_MOVE or a STOP_ALL on arrival and samples the plan
// from its next 20 ms velocity tick on (behaviour.playback_tick_ms;
// docs/devices/dmc16.md "The 20 ms velocity tick"), so where a motor stops
// depends on the ticks between the two, not on the millisecond each came:
// measured on the real firmware, a move at 2000 steps/s and 4000 steps/s^2
// stopped 600 ms after its answer came to rest 1200 steps on every time
// (docs/calibration.md). Its STOP_ALL brakes at |velocity| per second where
// that is harder than the max acceleration (behaviour.stop_all_within_ms).
TEST(Dmc16Behaviour, DirectMovesAndStopsStartOnTheVelocityTick) {
  // Where motor 2 rests: MOVE at `move_ms`, STOP_ALL at `stop_ms` (device clock).
  auto rest = [](uint32_t tick_ms, int64_t move_ms, int64_t stop_ms, uint32_t v, uint32_t a) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.playback_tick_ms = tick_ms;
    p.behaviour.stop_all_within_ms = 1000;
    Host h(p);
    EXPECT_EQ(h.Request(dmc::MotorSetSpeed{2, v, a}), kOk);
    h.RunFor(move_ms * kNsPerMs - h.now());
    // MOVE's answer (MOTOR STATUS) and the status after it say moving,
    // though the first step waits for the tick.
    const uint32_t mv = h.Send(dmc::MotorMove{2, 100000});
    const auto* moved = std::get_if<dmc::MotorMoveResponse>(&h.Reply(mv).msg);
    EXPECT_TRUE(moved != nullptr && moved->moving == 1);
    const uint32_t st = h.Send(dmc::MotorStatusRequest{});
    const auto* status = std::get_if<dmc::MotorStatusResponse>(&h.Reply(st).msg);
    EXPECT_TRUE(status != nullptr && (status->moving_bits & 2u) != 0);
    h.RunFor(stop_ms * kNsPerMs - h.now());
    EXPECT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
    h.Settle();
    return h.Pos(2);
  };
  // On the tick: MOVE at 5 ms starts at 20 ms; a STOP_ALL anywhere in
  // (600, 620) ms starts at 620: 30 ticks of motion, 500 + 200 steps, then
  // 500 steps of braking, whatever the millisecond.
  for (const int64_t stop_ms : {601, 607, 613, 619}) {
    SCOPED_TRACE("STOP_ALL at " + std::to_string(stop_ms) + " ms");
    EXPECT_EQ(rest(20, 5, stop_ms, 2000, 4000), 1200);
  }
  // One tick later, 40 steps more.
  EXPECT_EQ(rest(20, 5, 621, 2000, 4000), 1240);
  // On arrival (no tick), every millisecond counts: 2 steps each.
  EXPECT_EQ(rest(0, 5, 601, 2000, 4000), 1192);
  EXPECT_EQ(rest(0, 5, 607, 2000, 4000), 1204);
  // At 1000 steps/s^2 the max acceleration would brake 2000 steps; within a
  // second it brakes at 2000 steps/s^2: 1000 steps. The move: 2 s up to speed
  // (2000 steps), 1 s at it.
  EXPECT_EQ(rest(20, 5, 3010, 2000, 1000), 2000 + 2000 + 1000);
}

// With the tick a moving motor reads where the device sent it for the tick
// under way: dmc-lite reports its motion core's plan, which its stepping
// core reaches at the next tick. Measured on the real firmware, a move at
// 4000 steps/s^2 reports 7, 28, 64, 115 steps every third tick (the plan at
// 60, 120, 180, 240 ms), truncated toward zero.
TEST(Dmc16Behaviour, AMovingMotorOnTheTickReadsThePlanAtTheNextTick) {
  Dmc16Profile p = SmallProfile();
  p.behaviour.playback_tick_ms = 20;
  p.behaviour.positions_truncate = true;
  Host h(p);
  ASSERT_EQ(h.Request(dmc::MotorSetSpeed{2, 2000, 4000}), kOk);
  h.RunFor(5 * kNsPerMs - h.now());
  h.Send(dmc::MotorMove{2, 100000});  // starts at 20 ms
  h.RunFor(10 * kNsPerMs);            // 15 ms: waiting for its tick
  EXPECT_EQ(Positions(h).at(1), 0);
  for (const int64_t plan_ms : {60, 120, 180, 240}) {
    // 10 ms before the tick that ends at plan_ms after the start.
    h.RunFor((20 + plan_ms - 10) * kNsPerMs - h.now());
    const double plan_s = static_cast<double>(plan_ms) / 1000.0;
    SCOPED_TRACE("plan at " + std::to_string(plan_ms) + " ms");
    EXPECT_EQ(Positions(h).at(1), static_cast<int32_t>(2000 * plan_s * plan_s));
    EXPECT_LT(h.Pos(2), Positions(h).at(1)) << "the steps themselves come a tick later";
  }
  // Without the tick: the motor's own step.
  p.behaviour.playback_tick_ms = 0;
  Host c(p);
  ASSERT_EQ(c.Request(dmc::MotorSetSpeed{2, 2000, 4000}), kOk);
  c.Send(dmc::MotorMove{2, 100000});
  c.RunMs(110);
  EXPECT_EQ(Positions(c).at(1), c.Pos(2));
}

// dmc-lite reports its position, a float between steps while a motor moves,
// truncated toward zero (behaviour.positions_truncate); the spec reading
// reports the step the motor is on (the nearest). At rest both read the step
// exactly: an uploaded frame reads back exactly (DMC-RT-016).
TEST(Dmc16Behaviour, PositionsTruncate) {
  for (const bool truncate : {false, true}) {
    SCOPED_TRACE(truncate ? "positions_truncate" : "spec");
    Dmc16Profile p = SmallProfile();
    p.behaviour.positions_truncate = truncate;
    Host h(p);
    ASSERT_EQ(h.Request(dmc::RtUploadMoveBegin{0, 2}), kOk);
    ASSERT_EQ(h.Request(dmc::RtUploadMoveAxis{1, 0, true, {200, -200, 300}}), kOk);
    ASSERT_EQ(h.Request(dmc::RtUploadMoveEnd{}), kOk);
    for (const uint32_t f : {0u, 1u, 2u}) {
      EXPECT_EQ(h.Request(dmc::RtPositionFrame{f}), kOk);
      h.Settle();
      EXPECT_EQ(Positions(h).at(0), f == 0 ? 200 : (f == 1 ? -200 : 300));
    }
    EXPECT_EQ(MoveTaken(h, 1, -3000), 1);
    EXPECT_EQ(MoveTaken(h, 2, 3000), 1);
    int differ = 0;
    for (int i = 0; i < 40; ++i) {
      h.RunFor(7 * kNsPerMs + 310'000);
      const std::vector<int32_t> r = Positions(h);
      for (int m = 1; m <= 2; ++m) {
        const sim::StepperMotor& motor = h.device().rig_ref().motor(m);
        if (!motor.IsMoving()) continue;
        const double x = static_cast<double>(motor.CurrentPlan().origin_steps()) +
                         motor.CurrentPlan().StateAt(h.now()).x_steps;
        const int64_t want = truncate ? static_cast<int64_t>(std::trunc(x)) : motor.Position();
        EXPECT_EQ(r.at(static_cast<size_t>(m - 1)), want) << "motor " << m << " at " << x;
        differ += want != motor.Position() ? 1 : 0;
      }
    }
    EXPECT_EQ(differ > 0, truncate) << "reads toward zero, not the nearest step";
    h.Settle();
    EXPECT_EQ(Positions(h).at(0), -3000);
    EXPECT_EQ(Positions(h).at(1), 3000);
  }
}

// unsolicited_id_zero (dmc-lite): every message the device sends unprompted
// carries ID 0; the spec reading numbers them (ERRATA 1.9).
TEST(Dmc16Behaviour, UnsolicitedMessagesCarryASequenceIdOrZero) {
  for (const bool zero : {false, true}) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.unsolicited_id_zero = zero;
    Host h(p);
    EXPECT_EQ(MoveTaken(h, 1, 500), 1);
    h.Settle();
    std::set<uint32_t> ids;
    for (const Out& o : h.out()) {
      if (o.id < 0x10000) ids.insert(o.id);
    }
    EXPECT_EQ(std::get_if<dmc::HiResponse>(&h.out().front().msg) != nullptr, true);
    if (zero) {
      EXPECT_EQ(ids, std::set<uint32_t>{0});
    } else {
      EXPECT_GT(ids.size(), 3u);
      EXPECT_EQ(ids.count(0), 0u);
      EXPECT_EQ(*ids.begin(), 1u) << "HI at power-on";
    }
  }
}

// --- how the reference firmware reads requests (Dmc16Behaviour; dmc-lite) ------------------

// A request of `type` with exactly `data` (any length).
uint32_t SendData(Host& h, uint32_t id, dmc::MsgType type, const wire::Bytes& data) {
  wire::Bytes frame;
  dmc::EncodeFrame(id, dmc::ToWire(type), data, frame);
  h.SendRaw(frame);
  return id;
}

// length_checks: the spec's ERR_GENERAL for data shorter than the layout,
// or dmc-lite's exact 5 bytes for MOVE and RESET_POSITION only, every other
// request reading what it lacks as zeros.
TEST(Dmc16Behaviour, LengthChecks) {
  using Lc = Dmc16Behaviour::LengthChecks;
  using T = dmc::MsgType;
  for (const Lc lc : {Lc::kSpec, Lc::kMoveAndResetOnly}) {
    const bool lite = lc == Lc::kMoveAndResetOnly;
    SCOPED_TRACE(lite ? "move_and_reset_only" : "spec");
    Dmc16Profile p = SmallProfile();
    p.behaviour.length_checks = lc;
    p.behaviour.set_speed_checked = !lite;
    p.behaviour.jog_speed_checked = !lite;
    Host h(p);
    const std::optional<AckCode> short_ok = lite ? kOk : AckCode::kErrGeneral;
    // GIO_OUT: a TRIGGERS cut short reads 0 (its two bytes are not used).
    ASSERT_EQ(h.Request(dmc::GioOut{3}), kOk);
    EXPECT_EQ(h.AckOf(SendData(h, 201, T::kGioOut, {1, 0})), short_ok);
    EXPECT_EQ(h.device().gio_ref().outputs(), lite ? 0u : 3u);
    ASSERT_EQ(h.Request(dmc::GioOut{3}), kOk);
    EXPECT_EQ(h.AckOf(SendData(h, 202, T::kGioOut, {})), short_ok);
    EXPECT_EQ(h.device().gio_ref().outputs(), lite ? 0u : 3u);
    // MOTOR_STOP without data names motor 0.
    EXPECT_EQ(h.AckOf(SendData(h, 203, T::kMotorStop, {})),
              lite ? AckCode::kErrRange : AckCode::kErrGeneral);
    // SET_SPEED without MAX ACCEL: MAX ACCEL 0, half the max velocity.
    EXPECT_EQ(h.AckOf(SendData(h, 204, T::kMotorSetSpeed, {2, 0xd0, 0x07, 0, 0})), short_ok);
    const sim::MotionProfile& mp = h.device().rig_ref().motor(2).profile();
    EXPECT_EQ(mp.max_velocity_steps_per_s, lite ? 2000 : 5000);
    EXPECT_EQ(mp.max_accel_steps_per_s2, lite ? 1000 : 10000);
    // JOG with only its MOTOR: SPEED 0 towards step 0, where motor 1 stands.
    EXPECT_EQ(h.AckOf(SendData(h, 205, T::kMotorJog, {1})), short_ok);
    // MOVE shorter or longer than 5 bytes: ERR_GENERAL in dmc-lite, and
    // the move is not made; the spec's reading ignores the extra byte.
    EXPECT_EQ(h.AckOf(SendData(h, 206, T::kMotorMove, {1, 0x10, 0})), AckCode::kErrGeneral);
    const Out& longer = h.Reply(SendData(h, 207, T::kMotorMove, {1, 0x10, 0, 0, 0, 9}));
    if (lite) {
      EXPECT_EQ(std::get<dmc::Ack>(longer.msg).code, dmc::ToWire(AckCode::kErrGeneral));
    } else {
      EXPECT_EQ(std::get<dmc::MotorMoveResponse>(longer.msg).moving, 1);
    }
    h.Settle();
    EXPECT_EQ(h.Pos(1), lite ? 0 : 16);
    // RESET_POSITION with a trailing byte: refused in dmc-lite.
    EXPECT_EQ(h.AckOf(SendData(h, 208, T::kMotorResetPosition, {2, 5, 0, 0, 0, 1})),
              lite ? AckCode::kErrGeneral : AckCode::kOk);
    EXPECT_EQ(h.Pos(2), lite ? 0 : 5);
    // ... and ERR_MOVING first while anything moves.
    ASSERT_EQ(MoveTaken(h, 1, 5000), 1);
    EXPECT_EQ(h.AckOf(SendData(h, 209, T::kMotorResetPosition, {2, 5})),
              lite ? AckCode::kErrMoving : AckCode::kErrGeneral);
    h.Settle();
    // Bytes after the layout of other requests are ignored either way.
    const Out& status = h.Reply(SendData(h, 210, T::kMotorStatus, {1}));
    EXPECT_NE(std::get_if<dmc::MotorStatusResponse>(&status.msg), nullptr);
  }
}

// set_speed_checked: MAX VELOCITY or MAX ACCEL 0 refused (spec reading), or
// taken as dmc-lite takes them: velocity at least 10, accel 0 as half of it.
TEST(Dmc16Behaviour, SetSpeedChecked) {
  Host spec(SmallProfile());
  EXPECT_EQ(spec.Request(dmc::MotorSetSpeed{1, 0, 100}), AckCode::kErrRange);
  EXPECT_EQ(spec.Request(dmc::MotorSetSpeed{1, 100, 0}), AckCode::kErrRange);
  EXPECT_EQ(spec.Request(dmc::MotorSetSpeed{1, 3, 100}), kOk);
  EXPECT_EQ(spec.device().rig_ref().motor(1).profile().max_velocity_steps_per_s, 3);
  Host lite(Switched([](Dmc16Behaviour& b) { b.set_speed_checked = false; }));
  const auto speeds = [&](uint32_t v, uint32_t a) {
    EXPECT_EQ(lite.Request(dmc::MotorSetSpeed{1, v, a}), kOk) << v << " " << a;
    const sim::MotionProfile& mp = lite.device().rig_ref().motor(1).profile();
    return std::pair(mp.max_velocity_steps_per_s, mp.max_accel_steps_per_s2);
  };
  EXPECT_EQ(speeds(0, 0), std::pair(10.0, 5.0));
  EXPECT_EQ(speeds(3, 100), std::pair(10.0, 100.0));
  EXPECT_EQ(speeds(2001, 0), std::pair(2001.0, 1000.5));
  EXPECT_EQ(speeds(2000, 4000), std::pair(2000.0, 4000.0));
  EXPECT_EQ(lite.Request(dmc::MotorSetSpeed{9, 0, 0}), AckCode::kErrRange);
}

// position_confirm: RESET_POSITION's confirming MOTOR_GET_POSITION after its
// ACK (spec) or before it, and then also on a MOVE to where a motor stands.
TEST(Dmc16Behaviour, PositionConfirm) {
  using Pc = Dmc16Behaviour::PositionConfirm;
  for (const Pc pc : {Pc::kAfterAck, Pc::kBeforeAck}) {
    const bool before = pc == Pc::kBeforeAck;
    SCOPED_TRACE(before ? "before_ack" : "after_ack");
    Dmc16Profile p = SmallProfile();
    p.behaviour.position_confirm = pc;
    Host h(p);
    size_t mark = h.out().size();
    const uint32_t id = h.Send(dmc::MotorResetPosition{2, 777});
    h.Settle();
    ASSERT_EQ(h.out().size(), mark + 2) << "the ACK and one update, nothing later";
    const Out& first = h.out()[mark];
    const Out& second = h.out()[mark + 1];
    const Out& ack = before ? second : first;
    const Out& update = before ? first : second;
    EXPECT_EQ(ack.id, id);
    EXPECT_EQ(std::get<dmc::Ack>(ack.msg).code, dmc::ToWire(AckCode::kOk));
    EXPECT_LT(update.id, 0x10000u);
    EXPECT_EQ(std::get<dmc::MotorPositionReport>(update.msg).positions_steps[1], 777);
    // A refused reset confirms nothing.
    mark = h.out().size();
    EXPECT_EQ(h.Request(dmc::MotorResetPosition{9, 1}), AckCode::kErrRange);
    EXPECT_EQ(h.out().size(), mark + 1);
    // MOVE to the step the motor stands on.
    mark = h.out().size();
    const uint32_t mv = h.Send(dmc::MotorMove{2, 777});
    ASSERT_EQ(h.out().size(), mark + (before ? 2 : 1));
    EXPECT_EQ(h.out().back().id, mv);
    if (before) {
      EXPECT_EQ(std::get<dmc::MotorPositionReport>(h.out()[mark].msg).positions_steps[1], 777);
    }
    // A MOVE elsewhere sends no positions before its answer.
    mark = h.out().size();
    h.Send(dmc::MotorMove{2, 800});
    EXPECT_EQ(h.out().size(), mark + 1);
    h.Settle();
  }
}

// jog_speed_scale: 1..10000 as 1 %..100 % (spec), or the max velocity and
// acceleration times SPEED/10000, at least 4 each, without bound (dmc-lite).
TEST(Dmc16Behaviour, JogSpeedScale) {
  // The velocity a jog towards a far destination settles at.
  const auto cruise = [](Dmc16Behaviour::JogSpeedScale scale, uint16_t speed) {
    Dmc16Profile p = SmallProfile();
    p.behaviour.jog_speed_checked = false;
    p.behaviour.jog_speed_scale = scale;
    Host h(p);
    EXPECT_EQ(h.Request(dmc::MotorSetSpeed{1, 2000, 4000}), kOk);
    EXPECT_EQ(h.Request(dmc::MotorJog{1, speed, 1'000'000}), kOk) << speed;
    h.RunMs(3000);
    return h.device().rig_ref().motor(1).Velocity();
  };
  using S = Dmc16Behaviour::JogSpeedScale;
  EXPECT_DOUBLE_EQ(cruise(S::kSpec, 10000), 2000);
  EXPECT_DOUBLE_EQ(cruise(S::kSpec, 20000), 2000);
  EXPECT_DOUBLE_EQ(cruise(S::kSpec, 0), 2000 * sim::JogSpeedFraction(1));
  EXPECT_DOUBLE_EQ(cruise(S::kSpec, 5000), 2000 * sim::JogSpeedFraction(5000));
  EXPECT_DOUBLE_EQ(cruise(S::kPer10000, 10000), 2000);
  EXPECT_DOUBLE_EQ(cruise(S::kPer10000, 5000), 1000);
  EXPECT_DOUBLE_EQ(cruise(S::kPer10000, 20000), 4000);
  EXPECT_DOUBLE_EQ(cruise(S::kPer10000, 1), 4);
  EXPECT_DOUBLE_EQ(cruise(S::kPer10000, 0), 4);
  // With SPEED checked, the range is the spec's on either scale.
  Host h(Switched([](Dmc16Behaviour& b) { b.jog_speed_scale = S::kPer10000; }));
  EXPECT_EQ(h.Request(dmc::MotorJog{1, 10001, 100}), AckCode::kErrRange);
}

// jog_horizon_ms: a JOG goes on to its DESTINATION (spec), or only as far as
// half a second's speeding up and cruising then braking would take it.
TEST(Dmc16Behaviour, JogHorizon) {
  for (const uint32_t horizon_ms : {0u, 500u}) {
    SCOPED_TRACE("jog_horizon_ms " + std::to_string(horizon_ms));
    Dmc16Profile p = SmallProfile();
    p.behaviour.jog_horizon_ms = horizon_ms;
    Host h(p);
    ASSERT_EQ(h.Request(dmc::MotorSetSpeed{1, 2000, 4000}), kOk);
    // From rest: 0.5 s to reach 2000 steps/s (500 steps), then braking (500).
    ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, 100000}), kOk);
    h.Settle();
    EXPECT_EQ(h.Pos(1), horizon_ms != 0 ? 1000 : 100000);
    // A nearer DESTINATION is reached either way.
    ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, 900}), kOk);
    h.Settle();
    EXPECT_EQ(h.Pos(1), 900);
    // Repeated while under way, the jog goes on: 600 ms in, braking at 1600
    // steps/s, a renewal reaches 0.1 s back up to 2000 steps/s (180 steps),
    // 0.4 s at it (800) and the braking (500) further.
    ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, 100000}), kOk);
    h.RunMs(600);
    const int64_t at = h.Pos(1);
    ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, 100000}), kOk);
    h.Settle();
    if (horizon_ms != 0) {
      EXPECT_NEAR(static_cast<double>(h.Pos(1)), static_cast<double>(at) + 180 + 800 + 500, 1);
    } else {
      EXPECT_EQ(h.Pos(1), 100000);
    }
    // Against the present motion: the spec's jog turns back, dmc-lite's stops.
    ASSERT_EQ(MoveTaken(h, 1, 200000), 1);
    h.RunMs(1000);
    const int64_t before = h.Pos(1);
    ASSERT_EQ(h.Request(dmc::MotorJog{1, 10000, 0}), kOk);
    h.Settle();
    if (horizon_ms != 0) {
      EXPECT_EQ(h.Pos(1), before + 500) << "braked from 2000 steps/s at 4000 steps/s^2";
    } else {
      EXPECT_EQ(h.Pos(1), 0);
    }
  }
}

// coupling: a flagged motor follows the motor before it (this project's
// reading), or drives the motor after it, which does not count those steps
// in its reported position until its own next motion ends (dmc-lite).
TEST(Dmc16Behaviour, CouplingDrivesTheNextMotorUncounted) {
  Host spec(SmallProfile());
  ASSERT_EQ(spec.Request(dmc::MotorConfigure{2, kCoupled}), kOk);
  ASSERT_EQ(MoveTaken(spec, 1, 400), 1);
  spec.Settle();
  EXPECT_EQ(Positions(spec), (std::vector<int32_t>{400, 400, 0, 0}));

  Host h(Switched([](Dmc16Behaviour& b) { b.coupling = Dmc16Behaviour::Coupling::kDrivesNext; }));
  ASSERT_EQ(h.Request(dmc::MotorConfigure{1, kOn}), kOk);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupled}), kOk);
  ASSERT_EQ(h.Request(dmc::MotorConfigure{3, kCoupled}), kOk);  // driven: drives nothing
  ASSERT_EQ(h.Request(dmc::MotorConfigure{4, kCoupled}), kOk);  // the last: none after it
  EXPECT_EQ(h.device().rig_ref().leader(3), 2);
  EXPECT_EQ(h.device().rig_ref().leader(4), 0);
  EXPECT_EQ(h.device().rig_ref().leader(2), 0);
  ASSERT_EQ(MoveTaken(h, 1, 400), 1);
  h.Settle();
  EXPECT_EQ(Positions(h), (std::vector<int32_t>{400, 0, 0, 0})) << "motor 2 is not driven";
  ASSERT_EQ(MoveTaken(h, 2, 300), 1);
  h.Settle();
  EXPECT_EQ(h.Pos(3), 300) << "motor 3 makes motor 2's steps";
  EXPECT_EQ(Positions(h), (std::vector<int32_t>{400, 300, 0, 0})) << "but reports none";
  // Reversed: motor 3 mirrors motor 2, still uncounted.
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupledReversed}), kOk);
  ASSERT_EQ(MoveTaken(h, 2, 400), 1);
  h.Settle();
  EXPECT_EQ(h.Pos(3), 200);
  EXPECT_EQ(Positions(h)[2], 0);
  // Let go, motor 3 still reports 0; its own moves are in reported steps.
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kOn}), kOk);
  EXPECT_EQ(Positions(h)[2], 0);
  const size_t mark = h.out().size();
  ASSERT_EQ(MoveTaken(h, 3, 5), 1);
  h.Settle();
  // At the end of its own move its count (205) is read again: a jump of 200
  // is an engine exception, sent once.
  EXPECT_EQ(h.Pos(3), 205);
  EXPECT_EQ(Positions(h)[2], 205);
  std::vector<dmc::MotorHardStop> stops;
  for (size_t k = mark; k < h.out().size(); ++k) {
    if (const auto* s = std::get_if<dmc::MotorHardStop>(&h.out()[k].msg)) stops.push_back(*s);
  }
  ASSERT_EQ(stops.size(), 1u);
  EXPECT_EQ(stops[0].reason, static_cast<uint8_t>(dmc::HardStopReason::kEngineException));
  EXPECT_EQ(stops[0].motor, std::optional<uint8_t>(3));
  // RESET_POSITION makes the count and the report agree at once.
  ASSERT_EQ(h.Request(dmc::MotorConfigure{2, kCoupled}), kOk);
  ASSERT_EQ(MoveTaken(h, 2, 0), 1);
  h.Settle();
  EXPECT_EQ(Positions(h)[2], 205);
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{3, 50}), kOk);
  EXPECT_EQ(Positions(h)[2], 50);
  EXPECT_EQ(h.Pos(3), 50);
}

// hard_stop_window_ms 0: a second STOP_ALL decelerates as the first.
TEST(Dmc16Motor, HardStopWindowZeroNeverHardStops) {
  Dmc16Profile p = SmallProfile();
  p.hard_stop_window_ms = 0;
  Host h(p);
  h.Send(dmc::MotorMove{1, 100000});
  h.RunMs(1000);
  EXPECT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
  EXPECT_EQ(h.Request(dmc::MotorStopAll{}), kOk);
  EXPECT_EQ(h.device().rig_ref().motor(1).CurrentPlan().EndNs() - h.now(), 500 * kNsPerMs);
}

// --- laws -------------------------------------------------------------------------------------

// A generator of host requests with arbitrary field values in their layouts.
rc::Gen<dmc::HostMessage> GenRequest() {
  using namespace rc;
  auto motor = gen::inRange<uint8_t>(0, 6);
  auto pos = gen::inRange<int32_t>(-3000, 3000);
  return gen::oneOf(
      gen::just(dmc::HostMessage{dmc::HiRequest{}}),
      gen::just(dmc::HostMessage{dmc::MotorStatusRequest{}}),
      gen::just(dmc::HostMessage{dmc::MotorGetPositionRequest{}}),
      gen::just(dmc::HostMessage{dmc::GioInRequest{}}), gen::just(dmc::HostMessage{dmc::RtGo{}}),
      gen::just(dmc::HostMessage{dmc::RtUploadMoveEnd{}}),
      gen::map(gen::pair(motor, pos),
               [](auto p) {
                 return dmc::HostMessage{dmc::MotorMove{p.first, p.second}};
               }),
      gen::map(motor, [](uint8_t m) { return dmc::HostMessage{dmc::MotorStop{m}}; }),
      gen::just(dmc::HostMessage{dmc::MotorStopAll{}}),
      gen::map(gen::pair(motor, pos),
               [](auto p) {
                 return dmc::HostMessage{dmc::MotorResetPosition{p.first, p.second}};
               }),
      gen::map(
          gen::tuple(motor, gen::inRange<uint16_t>(0, 10002), pos),
          [](auto t) {
            return dmc::HostMessage{dmc::MotorJog{std::get<0>(t), std::get<1>(t), std::get<2>(t)}};
          }),
      gen::map(gen::pair(motor, gen::arbitrary<uint8_t>()),
               [](auto p) {
                 return dmc::HostMessage{dmc::MotorConfigure{p.first, p.second}};
               }),
      gen::map(gen::pair(gen::inRange<uint32_t>(0, 30), gen::inRange<uint32_t>(0, 30)),
               [](auto p) {
                 return dmc::HostMessage{dmc::RtUploadMoveBegin{p.first, p.second}};
               }),
      gen::map(gen::pair(motor, gen::inRange<uint32_t>(0, 40)),
               [](auto p) {
                 return dmc::HostMessage{dmc::RtUploadMoveAxis{p.first, p.second, true, {7, 9}}};
               }),
      gen::map(gen::inRange<uint32_t>(0, 40),
               [](uint32_t f) { return dmc::HostMessage{dmc::RtPositionFrame{f}}; }),
      gen::map(
          gen::pair(gen::inRange<uint32_t>(0, 40), gen::inRange<uint32_t>(0, 40)),
          [](auto p) { return dmc::HostMessage{RunMove(p.first, p.second, 24000, 200, 200)}; }),
      gen::map(gen::inRange<uint32_t>(0, 40),
               [](uint32_t f) {
                 return dmc::HostMessage{dmc::RtJogAll{24000, f}};
               }),
      gen::map(gen::inRange<uint16_t>(0, 0x300),
               [](uint16_t t) {
                 return dmc::HostMessage{dmc::Unknown{t, {}}};
               }),
      gen::map(gen::arbitrary<uint32_t>(),
               [](uint32_t t) { return dmc::HostMessage{dmc::GioOut{t}}; }));
}

RC_GTEST_PROP(Dmc16Laws, EveryRequestGetsExactlyOneAnswerWithItsIdAndALegalType, ()) {
  const auto requests = *rc::gen::container<std::vector<dmc::HostMessage>>(GenRequest());
  const auto gaps_ms =
      *rc::gen::container<std::vector<int>>(requests.size(), rc::gen::inRange(0, 400));
  Host h(SmallProfile());
  std::map<uint32_t, uint16_t> sent;  // id -> type
  for (size_t i = 0; i < requests.size(); ++i) {
    const uint16_t type = dmc::TypeOf(requests[i]);
    if (std::holds_alternative<dmc::Unknown>(requests[i]) && dmc::IsKnownType(type)) {
      continue;  // a known type with an empty body is a different request
    }
    sent[h.Send(requests[i])] = type;
    h.RunMs(gaps_ms[i]);
  }
  h.Settle();
  std::map<uint32_t, int> answers;
  for (const Out& o : h.out()) {
    auto it = sent.find(o.id);
    if (it == sent.end()) {
      RC_ASSERT(o.id < 0x10000u);  // unsolicited: a device-side ID
      continue;
    }
    ++answers[o.id];
    const uint16_t base = static_cast<uint16_t>(o.type & ~dmc::kFlagAck);
    RC_ASSERT(base == it->second);
  }
  for (const auto& [id, type] : sent) RC_ASSERT(answers[id] == 1);
}

RC_GTEST_PROP(Dmc16Laws, AnyChunkingGivesTheSameOutput, ()) {
  const auto requests = *rc::gen::container<std::vector<dmc::HostMessage>>(GenRequest());
  wire::Bytes stream;
  uint32_t id = 0x20000;
  for (const auto& r : requests) dmc::Encode(id++, r, stream);
  const auto cuts =
      *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(0, stream.size() + 1));
  Host whole(SmallProfile());
  whole.SendRaw(stream);
  Host pieces(SmallProfile());
  std::vector<size_t> c = cuts;
  c.push_back(0);
  c.push_back(stream.size());
  std::sort(c.begin(), c.end());
  for (size_t i = 0; i + 1 < c.size(); ++i) {
    pieces.SendRaw(wire::Bytes(stream.begin() + static_cast<long>(c[i]),
                               stream.begin() + static_cast<long>(c[i + 1])));
  }
  whole.Settle();
  pieces.Settle();
  RC_ASSERT(whole.out().size() == pieces.out().size());
  for (size_t i = 0; i < whole.out().size(); ++i) {
    RC_ASSERT(whole.out()[i].id == pieces.out()[i].id);
    RC_ASSERT(whole.out()[i].type == pieces.out()[i].type);
    RC_ASSERT(whole.out()[i].msg == pieces.out()[i].msg);
  }
}

RC_GTEST_PROP(Dmc16Laws, NoiseNeverCrashesAndGoodFramesAfterItAreAnswered, ()) {
  const auto noise = *rc::gen::container<std::vector<uint8_t>>(rc::gen::arbitrary<uint8_t>());
  Host h(SmallProfile());
  h.SendRaw(noise);
  // A frame cut short by noise may swallow bytes; the decoder resyncs from
  // the next marker, so a clean request after enough idle bytes is answered.
  h.device().OnHostLink(false);
  h.device().OnHostLink(true);
  const uint32_t id = h.Send(dmc::HiRequest{});
  h.Settle();
  int n = 0;
  for (const Out& o : h.out()) n += o.id == id ? 1 : 0;
  RC_ASSERT(n == 1);
}

// Noise biased towards the marker bytes, so false "DF" candidates are common.
rc::Gen<wire::Bytes> GenMarkerNoise() {
  return rc::gen::container<wire::Bytes>(rc::gen::weightedOneOf<uint8_t>(
      {{4, rc::gen::arbitrary<uint8_t>()},
       {1, rc::gen::just<uint8_t>('D')},
       {1, rc::gen::just<uint8_t>('F')},
       {1, rc::gen::elementOf(std::vector<uint8_t>{0x00, 0x01, 0x30, 0x80})}}));
}

// Requests with IDs no noise-made answer is likely to carry.
std::map<uint32_t, uint16_t> SendGoodRequests(Host& h, const std::vector<dmc::HostMessage>& m,
                                              wire::Bytes* stream) {
  std::map<uint32_t, uint16_t> sent;
  uint32_t id = 0xa5000000u;
  for (const dmc::HostMessage& r : m) {
    const uint16_t type = dmc::TypeOf(r);
    if (std::holds_alternative<dmc::Unknown>(r) && dmc::IsKnownType(type)) continue;
    dmc::Encode(id, r, *stream);
    sent[id++] = type;
  }
  h.SendRaw(*stream);
  return sent;
}

// Resync (Message Format; docs/protocol-notes.md "Resync", "Idle line"): after
// any noise, good requests sent right behind it are each answered exactly
// once by the time the line has been idle for the gap; and no answer carries
// a Type made of noise: anything but an answer to them or an unsolicited
// message is ERR_CHECKSUM for a header a request can have.
RC_GTEST_PROP(Dmc16Laws, AfterNoiseEveryGoodRequestIsAnsweredOnceAndNothingImplausible, ()) {
  const auto noise = *GenMarkerNoise();
  const auto requests = *rc::gen::container<std::vector<dmc::HostMessage>>(GenRequest());
  Host h(SmallProfile());
  h.SendRaw(noise);
  wire::Bytes stream;
  const auto sent = SendGoodRequests(h, requests, &stream);
  // Not the law's case: a false frame in the noise that happens to check out.
  bool noise_frame = false;
  for (const dmc::StreamEvent& e : dmc::DecodeStream(noise, /*finish=*/false)) {
    noise_frame = noise_frame || std::holds_alternative<dmc::Frame>(e);
  }
  RC_PRE(!noise_frame);
  h.Settle();
  std::map<uint32_t, int> answers;
  for (const Out& o : h.out()) {
    if (sent.count(o.id) != 0) {
      ++answers[o.id];
      continue;
    }
    if (o.id < 0x10000u && (o.type & dmc::kFlagAck) == 0) continue;  // unsolicited
    const auto* a = std::get_if<dmc::Ack>(&o.msg);
    RC_ASSERT(a != nullptr);
    RC_ASSERT(a->code == dmc::ToWire(AckCode::kErrChecksum));
    RC_ASSERT(dmc::PlausibleRequestHeader(a->type));
  }
  for (const auto& [id, type] : sent) RC_ASSERT(answers[id] == 1);
}

// Without rescanning (dmc-lite) a false "DF" may swallow what follows it, but
// the idle gap ends it: requests after noise and a gap are each answered once.
RC_GTEST_PROP(Dmc16Laws, WithoutRescanRequestsAfterNoiseAndAnIdleGapAreAnsweredOnce, ()) {
  const auto noise = *GenMarkerNoise();
  const auto requests = *rc::gen::container<std::vector<dmc::HostMessage>>(GenRequest());
  Dmc16Profile p = SmallProfile();
  p.behaviour.rescan_after_bad_frame = false;
  p.behaviour.receive_buffer_bytes = 2048;
  Host h(p);
  h.SendRaw(noise);
  h.RunFor(Dmc16::kLineIdleGapNs);
  wire::Bytes stream;
  const auto sent = SendGoodRequests(h, requests, &stream);
  h.Settle();
  std::map<uint32_t, int> answers;
  for (const Out& o : h.out()) answers[o.id] += sent.count(o.id) != 0 ? 1 : 0;
  for (const auto& [id, type] : sent) RC_ASSERT(answers[id] == 1);
}

TEST(Dmc16State, StateReportsPositionsModeAndCounters) {
  Host h(SmallProfile());
  ASSERT_EQ(h.Request(dmc::MotorResetPosition{3, 42}), kOk);
  const nlohmann::json s = h.device().State();
  EXPECT_EQ(s["model"], "dmc16");
  EXPECT_EQ(s["mode"], "idle");
  EXPECT_EQ(s["motors"][2]["position_steps"], 42);
  EXPECT_EQ(s["stats"]["requests"], 1);
}

}  // namespace
}  // namespace moco::devices
