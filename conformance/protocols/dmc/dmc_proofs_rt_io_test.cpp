// Proving tests of the DMC v2 real-time output clauses (dmc-v2-protocol.txt
// "MSG_RT_UPLOAD_MOVE_DMX", "MSG_RT_UPLOAD_MOVE_TRIGGERS",
// "MSG_RT_POSITION_FRAME", "MSG_RT_RUN_MOVE" SYNC DMX, BLOOP, FLAGS and camera
// angles, "MSG_FLAG_ACK" ERR_PREROLL / ERR_POSTROLL): the real emulated DMC-16
// with one planted fault (a request it misreads, or an answer it garbles),
// caught by the rule that names it (conformance/core/rule_proof_testing.h);
// the correct device passes every one of these rules, and a target whose
// outputs cannot be read leaves the output rules not exercised.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dmc/dmc_broken_device_testing.h"
#include "conformance/protocols/dmc/dmc_protocol.h"

namespace moco::conformance {
namespace {

using proof::FailedMusts;

using namespace dmc_testing;  // BrokenDmc16, RunBroken, PassThrough
using dmc::AckCode;

// What a misreading device makes of one host request.
struct Reading {
  std::optional<dmc::HostMessage> instead;  // acts on this request (same ID) instead
  std::optional<uint16_t> refuse;           // answers this code and does nothing
  std::vector<dmc::HostMessage> also;       // carries these out first, unanswered
  std::vector<dmc::HostMessage> after;      // carries these out next, unanswered
};
using Misreading = std::function<Reading(const dmc::HostMessage&)>;

// An output fault that may look at the request a frame answers (nullptr:
// unsolicited, or a request that did not decode); `raw` emptied: never sent.
using AnswerBreakage =
    std::function<void(const dmc::FrameRef& f, const dmc::HostMessage* request, wire::Bytes& raw)>;

struct MisreadState {
  std::map<uint32_t, dmc::HostMessage> requests;  // by ID, as the host sent them
  std::map<uint32_t, dmc::Ack> refusals;          // answers replacing a MOTOR_STATUS answer
  std::set<uint32_t> hidden;                      // requests the host never sent
  uint32_t next_hidden = 0xfff00000;
};

// Runs the DMC-16 reading each request through `misread` and writing each
// frame through `answer` (as dmc_proofs_motion_test.cpp does). A refused
// request reaches the device as a MOTOR_STATUS under the same ID and its
// answer goes out as the refusal; answers to made-up requests are dropped.
RunReport RunMisreading(Misreading misread, AnswerBreakage answer, const std::string& cases,
                        const std::string& profile = "") {
  auto st = std::make_shared<MisreadState>();
  const InputBreakage in = [st, misread](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    const auto f = dmc::DecodeFrame(bytes);  // the host writes whole frames in-process
    if (!f.ok()) return out;
    const auto m = dmc::DecodeHostMessage(f.value());
    if (!m.ok()) return out;
    st->requests[f.value().id] = m.value();
    if (!misread) return out;
    const Reading r = misread(m.value());
    wire::Bytes changed;
    auto hide = [&](const dmc::HostMessage& extra) {
      const uint32_t id = st->next_hidden++;
      st->hidden.insert(id);
      const wire::Bytes b = dmc::Encode(id, extra);
      changed.insert(changed.end(), b.begin(), b.end());
    };
    for (const dmc::HostMessage& extra : r.also) hide(extra);
    wire::Bytes own = out;
    if (r.refuse) {
      st->refusals[f.value().id] = dmc::Ack{f.value().type, *r.refuse};
      own = dmc::Encode(f.value().id, dmc::HostMessage{dmc::MotorStatusRequest{}});
    } else if (r.instead) {
      own = dmc::Encode(f.value().id, *r.instead);
    }
    changed.insert(changed.end(), own.begin(), own.end());
    for (const dmc::HostMessage& extra : r.after) hide(extra);
    return changed;
  };
  const Breakage outb = [st, answer](const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler&,
                                     devices::ByteSink& out) {
    if (st->hidden.count(f.id) != 0) return;
    if (auto it = st->refusals.find(f.id);
        it != st->refusals.end() && f.type == ToWire(MsgType::kMotorStatus)) {
      out.Write(dmc::Encode(f.id, dmc::DeviceMessage{it->second}));
      st->refusals.erase(it);
      return;
    }
    if (answer) {
      const bool solicited = f.id >= DmcHost::kFirstHostId;
      auto it = solicited ? st->requests.find(f.id) : st->requests.end();
      answer(f, it != st->requests.end() ? &it->second : nullptr, raw);
    }
    if (!raw.empty()) out.Write(raw);
  };
  RunOptions o;
  o.cases = cases;
  return RunBroken(outb, o, profile, in);
}

template <typename T>
const T* Is(const dmc::HostMessage* m) {
  return m != nullptr ? std::get_if<T>(m) : nullptr;
}

template <typename T>
const T* Is(const dmc::HostMessage& m) {
  return std::get_if<T>(&m);
}

uint16_t Code(AckCode c) { return ToWire(c); }

// An answer breakage: the ACK of a request of type T with code `from` goes
// out with code `to`.
template <typename T>
AnswerBreakage AckRecoded(AckCode from, AckCode to) {
  return [from, to](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
    if (Is<T>(req) == nullptr) return;
    const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
    if (!m.ok()) return;
    const auto* a = std::get_if<dmc::Ack>(&m.value());
    if (a == nullptr || a->code != Code(from)) return;
    raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{a->type, Code(to)}});
  };
}

// A RUN_MOVE misread by `change` (the rest read as sent).
Misreading RunMoveAs(std::function<void(dmc::RtRunMove&)> change) {
  return [change](const dmc::HostMessage& m) {
    Reading d;
    if (const auto* run = Is<dmc::RtRunMove>(m)) {
      dmc::RtRunMove changed = *run;
      change(changed);
      if (!(changed == *run)) d.instead = changed;
    }
    return d;
  };
}

const std::set<std::string> kIoRules = {"DMC-DMX-005", "DMC-DMX-006", "DMC-DMX-007", "DMC-DMX-008",
                                        "DMC-DMX-009", "DMC-DMX-010", "DMC-DMX-011", "DMC-RT-017",
                                        "DMC-RT-018",  "DMC-RT-019",  "DMC-RT-020",  "DMC-RT-021",
                                        "DMC-RT-022",  "DMC-RT-023",  "DMC-RT-024",  "DMC-RT-025",
                                        "DMC-RT-026",  "DMC-RT-027",  "DMC-RT-028",  "DMC-RT-029"};
// The rules judged on what the runner reads of the outputs.
const std::set<std::string> kOutputRules = {
    "DMC-DMX-007", "DMC-DMX-008", "DMC-DMX-009", "DMC-DMX-010", "DMC-DMX-011",
    "DMC-RT-019",  "DMC-RT-020",  "DMC-RT-022",  "DMC-RT-023",  "DMC-RT-025"};
constexpr const char* kIoCases =
    "rt/upload-dmx,rt/sync-run,rt/triggers,rt/camera-stills,rt/camera-video,rt/roll-limits";

// ------------------------------------------------------------------ the correct device

TEST(RtIoProof, TheEmulatedDmc16PassesEveryRealTimeOutputRule) {
  const RunReport r = RunMisreading({}, {}, kIoCases);
  for (const std::string& id : kIoRules) {
    ASSERT_TRUE(r.rules.count(id)) << id;
    EXPECT_EQ(r.rules.at(id).status, Status::kPass) << id << "\n" << ConsoleReport(r, false);
  }
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// An in-process device behind a target that cannot read its outputs, as an
// external device is.
class BlindTarget final : public Target {
 public:
  BlindTarget()
      : inner_("dmc16", [](sim::Scheduler& s, devices::ByteSink& out) {
          return devices::CreateDevice("dmc16", "", s, out);
        }) {}
  std::string Name() const override { return "blind:" + inner_.Name(); }
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  std::optional<std::string> Open() override { return inner_.Open(); }
  void Restart() override { inner_.Restart(); }
  TimeNs Now() const override { return inner_.Now(); }
  bool Send(wire::ByteView bytes) override { return inner_.Send(bytes); }
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override {
    return inner_.Receive(deadline_ns, out);
  }

 private:
  InProcessTarget inner_;
};

TEST(RtIoProof, OutputRulesAreNotExercisedWhereTheOutputsCannotBeRead) {
  BlindTarget target;
  ASSERT_FALSE(target.Open().has_value());
  RunOptions o;
  o.cases = kIoCases;
  const RunReport r = RunDmc(target, o);
  for (const std::string& id : kIoRules) {
    ASSERT_TRUE(r.rules.count(id)) << id;
    const Status want = kOutputRules.count(id) ? Status::kNotExercised : Status::kPass;
    EXPECT_EQ(r.rules.at(id).status, want) << id << "\n" << ConsoleReport(r, false);
  }
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ DMX upload

TEST(RtIoProof, DmxSectionsRefusedAreCaughtByDmx005) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::RtUploadMoveDmx>(m)) d.refuse = Code(AckCode::kErrUnsupported);
        return d;
      },
      {}, "rt/upload-dmx");
  ExpectCaught(r, "DMC-DMX-005");
}

TEST(RtIoProof, DmxSectionsForMissingChannelsAckedOkAreCaughtByDmx006) {
  const RunReport r = RunMisreading(
      {}, AckRecoded<dmc::RtUploadMoveDmx>(AckCode::kErrRange, AckCode::kOk), "rt/upload-dmx");
  ExpectCaught(r, "DMC-DMX-006");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(RtIoProof, APositionFrameThatLeavesTheLightsOutIsCaughtByDmx007) {
  // After RT_POSITION_FRAME 3 the device switches channels 1 and 2 off.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* p = Is<dmc::RtPositionFrame>(m); p != nullptr && p->frame == 3) {
          d.after.push_back(dmc::Dmx{0, 1, {0, 0}});
        }
        return d;
      },
      {}, "rt/upload-dmx");
  ExpectCaught(r, "DMC-DMX-007");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-DMX-007"}) << ConsoleReport(r, false);
}

TEST(RtIoProof, DmxThatGoesDarkAfterItsLastSetIsCaughtByDmx008) {
  // The device does not repeat a channel's final level: past the last set it
  // plays 0 (as if a last set of one 0 followed).
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* s = Is<dmc::RtUploadMoveDmx>(m);
            s != nullptr && s->last_set && s->channel >= 1 && s->start_index < 20) {
          dmc::RtUploadMoveDmx open = *s;
          open.last_set = false;
          d.instead = open;
          d.after.push_back(dmc::RtUploadMoveDmx{
              s->channel, s->start_index + static_cast<uint32_t>(s->levels.size()), true, {0}});
        }
        return d;
      },
      {}, "rt/upload-dmx");
  ExpectCaught(r, "DMC-DMX-008");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-DMX-008"}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ SYNC DMX

TEST(RtIoProof, ARunThatIgnoresSyncDmxIsCaughtByDmx009) {
  const RunReport r =
      RunMisreading(RunMoveAs([](dmc::RtRunMove& run) { run.sync_dmx = 0; }), {}, "rt/sync-run");
  ExpectCaught(r, "DMC-DMX-009");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-DMX-009"}) << ConsoleReport(r, false);
}

TEST(RtIoProof, ARunThatPlaysDmxWithSyncDmxZeroIsCaughtByDmx010) {
  const RunReport r =
      RunMisreading(RunMoveAs([](dmc::RtRunMove& run) { run.sync_dmx = 1; }), {}, "rt/sync-run");
  ExpectCaught(r, "DMC-DMX-010");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ triggers

TEST(RtIoProof, TriggerSectionsRefusedAreCaughtByRt017) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::RtUploadMoveTriggers>(m)) d.refuse = Code(AckCode::kErrUnsupported);
        return d;
      },
      {}, "rt/triggers");
  ExpectCaught(r, "DMC-RT-017");
}

TEST(RtIoProof, TriggersPastTheUploadAckedOkAreCaughtByRt018) {
  const RunReport r = RunMisreading(
      {}, AckRecoded<dmc::RtUploadMoveTriggers>(AckCode::kErrRange, AckCode::kOk), "rt/triggers");
  ExpectCaught(r, "DMC-RT-018");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// Every trigger point of RT_UPLOAD_MOVE_TRIGGERS read one frame later.
Reading LateTriggers(const dmc::HostMessage& m) {
  Reading d;
  if (const auto* t = Is<dmc::RtUploadMoveTriggers>(m)) {
    dmc::RtUploadMoveTriggers late = *t;
    for (dmc::TriggerPoint& p : late.points) ++p.frame_index;
    d.instead = late;
  }
  return d;
}

TEST(RtIoProof, TriggersPlayedAFrameLateAreCaughtByRt019) {
  const RunReport r = RunMisreading(LateTriggers, {}, "rt/triggers");
  ExpectCaught(r, "DMC-RT-019");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// On a velocity tick (the dmc-lite profile) the frame reports carry
// fractional MOVE TIMEs and name only some frames: the outputs are read by
// the frame clock those reports give, so the late triggers are still caught,
// and the same device playing them on time passes.
TEST(RtIoProof, TriggersPlayedAFrameLateOnAVelocityTickAreCaughtByRt019) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string lite =
      std::string(root != nullptr ? root : ".") + "/fixtures/profiles/dmc-lite.json";
  const RunReport on_time = RunMisreading({}, {}, "rt/triggers", lite);
  ASSERT_TRUE(on_time.rules.count("DMC-RT-019"));
  EXPECT_EQ(on_time.rules.at("DMC-RT-019").status, Status::kPass) << ConsoleReport(on_time, false);
  const RunReport r = RunMisreading(LateTriggers, {}, "rt/triggers", lite);
  ExpectCaught(r, "DMC-RT-019");
}

TEST(RtIoProof, ARunWithoutItsBloopIsCaughtByRt020) {
  const RunReport r = RunMisreading(RunMoveAs([](dmc::RtRunMove& run) { run.bloop_outputs = 0; }),
                                    {}, "rt/triggers");
  ExpectCaught(r, "DMC-RT-020");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ camera

TEST(RtIoProof, CameraFlagsRefusedAreCaughtByRt021) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        const auto* run = Is<dmc::RtRunMove>(m);
        if (run != nullptr && (run->flags.value_or(0) & 0x30) != 0) {
          d.refuse = Code(AckCode::kErrRange);
        }
        return d;
      },
      {}, "rt/camera-*");
  ExpectCaught(r, "DMC-RT-021");
}

TEST(RtIoProof, StillsShotAsVideoAreCaughtByRt022) {
  const RunReport r = RunMisreading(RunMoveAs([](dmc::RtRunMove& run) {
                                      if (run.flags == dmc::kPlayCameraStills) {
                                        run.flags = dmc::kPlayCameraVideo;
                                      }
                                    }),
                                    {}, "rt/camera-stills");
  ExpectCaught(r, "DMC-RT-022");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RT-022"}) << ConsoleReport(r, false);
}

TEST(RtIoProof, StillsOpenFromTheWrongAngleAreCaughtByRt023) {
  // The device opens at 0 degrees and closes at 180, whatever it is sent.
  const RunReport r = RunMisreading(
      RunMoveAs([](dmc::RtRunMove& run) {
        if (run.flags == dmc::kPlayCameraStills && run.camera_close_angle_deg == 270) {
          run.camera_open_angle_deg = 0;
          run.camera_close_angle_deg = 180;
        }
      }),
      {}, "rt/camera-stills");
  ExpectCaught(r, "DMC-RT-023");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(RtIoProof, AnAnglePast360RefusedWithErrGeneralIsCaughtByRt024) {
  const RunReport r = RunMisreading(
      {}, AckRecoded<dmc::RtRunMove>(AckCode::kErrRange, AckCode::kErrGeneral), "rt/camera-stills");
  ExpectCaught(r, "DMC-RT-024");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(RtIoProof, VideoTriggeredEveryFrameIsCaughtByRt025) {
  // The device reads the video flag as stills (no angles: the whole frame).
  const RunReport r = RunMisreading(RunMoveAs([](dmc::RtRunMove& run) {
                                      if (run.flags == dmc::kPlayCameraVideo) {
                                        run.flags = dmc::kPlayCameraStills;
                                      }
                                    }),
                                    {}, "rt/camera-video");
  ExpectCaught(r, "DMC-RT-025");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ pre-/post-roll

TEST(RtIoProof, SwappedRollCodesAreCaughtByRt026AndRt027) {
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        if (Is<dmc::RtRunMove>(req) == nullptr) return;
        const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
        if (!m.ok()) return;
        const auto* a = std::get_if<dmc::Ack>(&m.value());
        if (a == nullptr) return;
        dmc::Ack swapped = *a;
        if (a->code == Code(AckCode::kErrPreroll)) swapped.code = Code(AckCode::kErrPostroll);
        if (a->code == Code(AckCode::kErrPostroll)) swapped.code = Code(AckCode::kErrPreroll);
        raw = dmc::Encode(f.id, dmc::DeviceMessage{swapped});
      },
      "rt/roll-limits");
  ExpectCaught(r, "DMC-RT-026");
  ExpectCaught(r, "DMC-RT-027");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(RtIoProof, ARunRefusedForItsPrerollThatMovesTheRigIsCaughtByRt028) {
  // ERR_PREROLL, but the rig is driven to frame 5 all the same.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* run = Is<dmc::RtRunMove>(m); run != nullptr && run->preroll_ms == 500) {
          d.also.push_back(dmc::RtPositionFrame{5});
          d.refuse = Code(AckCode::kErrPreroll);
        }
        return d;
      },
      {}, "rt/roll-limits");
  ExpectCaught(r, "DMC-RT-028");
}

TEST(RtIoProof, ARunWithinTheLimitsRefusedIsCaughtByRt029) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* run = Is<dmc::RtRunMove>(m); run != nullptr && run->preroll_ms == 100) {
          d.refuse = Code(AckCode::kErrPreroll);
        }
        return d;
      },
      {}, "rt/roll-limits");
  ExpectCaught(r, "DMC-RT-029");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RT-029"}) << ConsoleReport(r, false);
}

}  // namespace
}  // namespace moco::conformance
