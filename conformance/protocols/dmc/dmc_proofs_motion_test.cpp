// Proving tests of the DMC v2 motion clauses (dmc-v2-protocol.txt
// "MSG_MOTOR_MOVE", "MSG_MOTOR_GET_POSITION", "MSG_MOTOR_RESET_POSITION",
// "MSG_MOTOR_STOP", "MSG_MOTOR_STOP_ALL", "MSG_MOTOR_SET_LIMITS", "MSG_GIO_*",
// "Real-time Moves", "MSG_VIRT_*"; ERRATA 1.6, 1.7, 1.11): the real emulated
// DMC-16 with one planted fault, caught by the rule that names it
// (conformance/core/rule_proof_testing.h), and by few others.
#include <gtest/gtest.h>

#include <algorithm>
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

using namespace dmc_testing;  // BrokenDmc16, RunBroken, Reencode, PassThrough
using dmc::AckCode;

// What a misreading device makes of one host request.
struct Reading {
  std::optional<dmc::HostMessage> instead;  // acts on this request (same ID) instead
  std::optional<uint16_t> refuse;           // answers this code and does nothing
  std::vector<dmc::HostMessage> also;       // carries these out first, unanswered
};
using Misreading = std::function<Reading(const dmc::HostMessage&)>;

// A device's output fault that may look at the request a frame answers
// (nullptr: unsolicited, or a request that did not decode).
using AnswerBreakage =
    std::function<void(const dmc::FrameRef& f, const dmc::HostMessage* request, wire::Bytes& raw)>;

struct MisreadState {
  std::map<uint32_t, dmc::HostMessage> requests;  // by ID, as the host sent them
  std::map<uint32_t, dmc::Ack> refusals;          // answers replacing a MOTOR_STATUS answer
  std::set<uint32_t> hidden;                      // requests the host never sent
  uint32_t next_hidden = 0xfff00000;
};

// Runs the DMC-16 (`profile`) reading each request through `misread` and
// writing each frame through `answer`. A refused request reaches the device as
// a MOTOR_STATUS under the same ID (so it acts on nothing) and its answer goes
// out as the refusal; the answers to the requests it makes up are dropped.
RunReport RunMisreading(Misreading misread, AnswerBreakage answer, RunOptions o,
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
    for (const dmc::HostMessage& extra : r.also) {
      const uint32_t id = st->next_hidden++;
      st->hidden.insert(id);
      const wire::Bytes b = dmc::Encode(id, extra);
      changed.insert(changed.end(), b.begin(), b.end());
    }
    wire::Bytes own = out;
    if (r.refuse) {
      st->refusals[f.value().id] = dmc::Ack{f.value().type, *r.refuse};
      own = dmc::Encode(f.value().id, dmc::HostMessage{dmc::MotorStatusRequest{}});
    } else if (r.instead) {
      own = dmc::Encode(f.value().id, *r.instead);
    }
    changed.insert(changed.end(), own.begin(), own.end());
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
    if (!raw.empty()) out.Write(raw);  // empty: the frame is never sent
  };
  return RunBroken(outb, o, profile, in);
}

RunOptions Cases(const std::string& glob) {
  RunOptions o;
  o.cases = glob;
  return o;
}

template <typename T>
const T* Is(const dmc::HostMessage* m) {
  return m != nullptr ? std::get_if<T>(m) : nullptr;
}

template <typename T>
const T* Is(const dmc::HostMessage& m) {
  return std::get_if<T>(&m);
}

// The frame as a device message of type T, when it is one.
template <typename T>
std::optional<T> Decoded(const dmc::FrameRef& f) {
  const auto m = dmc::DecodeDeviceMessage(f.type, f.data);
  if (!m.ok()) return std::nullopt;
  if (const T* t = std::get_if<T>(&m.value())) return *t;
  return std::nullopt;
}

bool IsUpdate(const dmc::FrameRef& f) {
  return f.type == ToWire(MsgType::kMotorGetPosition) && f.id < DmcHost::kFirstHostId;
}

uint16_t Code(AckCode c) { return ToWire(c); }

// ------------------------------------------------------------------ MOVE

TEST(MotionProof, AMoveAnsweredNotMovingIsCaughtByMove002) {
  // "MOTOR STATUS BYTE 1=motor moving": the device answers 0 for a move it makes.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (Decoded<dmc::MotorMoveResponse>(f)) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::MotorMoveResponse{0}});
        }
      },
      Cases("motor/move"));
  ExpectCaught(r, "DMC-MOVE-002");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, AMotorThatStopsShortOfItsTargetIsCaughtByMove003) {
  // The device moves every motor 7 steps short of the position it was sent to.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* mv = Is<dmc::MotorMove>(m)) {
          d.instead = dmc::MotorMove{mv->motor, mv->position_steps - 7};
        }
        return d;
      },
      {}, Cases("motor/move"));
  ExpectCaught(r, "DMC-MOVE-003");
  // MOTOR_GET_POSITION and the last update agree on where the motor rests:
  // the reports are right, the motion is not.
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-MOVE-003"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AMoveOfMotorOneThatAlsoMovesMotorTwoIsCaughtByMove004) {
  // The device drives motor 2 to every position motor 1 is sent to.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* mv = Is<dmc::MotorMove>(m); mv != nullptr && mv->motor == 1) {
          d.also.push_back(dmc::MotorMove{2, mv->position_steps});
        }
        return d;
      },
      {}, Cases("motor/move"));
  ExpectCaught(r, "DMC-MOVE-004");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-MOVE-004"}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ POS

TEST(MotionProof, PositionUpdatesOneMotorShortAreCaughtByPos001) {
  // MOVE TIME and 15 positions from a 16-motor device: the last DWORD is cut.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (IsUpdate(f) && f.data.size() >= 8) {
          raw = Reencode(f, f.id, f.data.first(f.data.size() - 4));
        }
      },
      Cases("motor/move"));
  ExpectCaught(r, "DMC-POS-001");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-POS-001"}) << ConsoleReport(r, false);
}

TEST(MotionProof, UpdatesThatLagOneBehindMissTheFinalPositionAndAreCaughtByPos004) {
  // Each update carries the positions of the update before it, so the last
  // one, after the motor stopped, still shows it short of where it rests.
  auto prev = std::make_shared<std::optional<dmc::MotorPositionReport>>();
  const RunReport r = RunMisreading(
      {},
      [prev](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (!IsUpdate(f)) return;
        auto now = Decoded<dmc::MotorPositionReport>(f);
        if (!now) return;
        if (*prev) {
          dmc::MotorPositionReport stale = **prev;
          stale.move_time_x1000 = now->move_time_x1000;
          raw = dmc::Encode(f.id, dmc::DeviceMessage{stale});
        }
        *prev = now;
      },
      Cases("motor/move"));
  ExpectCaught(r, "DMC-POS-004");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, UpdatesShowingAnOvershootPastTheTargetAreCaughtByPos005) {
  // The device overshoots: while motor 1 is on its way its updates show it as
  // far past the target as it still is short of it; it settles on the target.
  auto target = std::make_shared<std::optional<int32_t>>();
  const RunReport r = RunMisreading(
      [target](const dmc::HostMessage& m) {
        if (const auto* mv = Is<dmc::MotorMove>(m); mv != nullptr && mv->motor == 1) {
          *target = mv->position_steps;
        }
        return Reading{};
      },
      [target](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (!IsUpdate(f) || !*target) return;
        auto p = Decoded<dmc::MotorPositionReport>(f);
        if (!p || p->positions_steps.empty()) return;
        int32_t& m1 = p->positions_steps[0];
        m1 = **target + (**target - m1);
        raw = dmc::Encode(f.id, dmc::DeviceMessage{*p});
      },
      Cases("motor/move"));
  ExpectCaught(r, "DMC-POS-005");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, APositionAnswerOneStepOffIsCaughtByPos006) {
  // The answer to MOTOR_GET_POSITION reports motor 1 a step past where it
  // is; the updates report it right.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        if (Is<dmc::MotorGetPositionRequest>(req) == nullptr) return;
        auto p = Decoded<dmc::MotorPositionReport>(f);
        if (!p || p->positions_steps.empty()) return;
        p->positions_steps[0] += 1;
        raw = dmc::Encode(f.id, dmc::DeviceMessage{*p});
      },
      Cases("motor/move"));
  ExpectCaught(r, "DMC-POS-006");
  // The last update shows the motor on its target: the answer is at fault,
  // not the motion.
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-POS-006"}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ RST

TEST(MotionProof, AResetPositionRefusedAtRestIsCaughtByRst001) {
  // The device answers ERR_MOVING to RESET_POSITION of a motor at rest.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::MotorResetPosition>(m)) d.refuse = Code(AckCode::kErrMoving);
        return d;
      },
      {}, Cases("motor/reset-position"));
  ExpectCaught(r, "DMC-RST-001");
  // A reset not made reports no new position either (RST-002, RST-003).
  const std::set<std::string> musts = FailedMusts(r);
  EXPECT_TRUE(musts.count("DMC-RST-001"));
  for (const std::string& id : musts) {
    EXPECT_TRUE(id == "DMC-RST-001" || id == "DMC-RST-003") << id;
  }
}

TEST(MotionProof, AResetPositionAckedButIgnoredIsCaughtByRst003) {
  // ACK OK, but the motor keeps its old position.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::MotorResetPosition>(m)) d.refuse = Code(AckCode::kOk);
        return d;
      },
      {}, Cases("motor/reset-position"));
  ExpectCaught(r, "DMC-RST-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RST-003"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AResetPositionThatMovesTheMotorIsCaughtByRst003) {
  // "This does not move the motor": this device drives it to the new value.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* rp = Is<dmc::MotorResetPosition>(m)) {
          d.also.push_back(dmc::MotorMove{rp->motor, rp->position_steps});
          d.refuse = Code(AckCode::kOk);
        }
        return d;
      },
      {}, Cases("motor/reset-position"));
  ExpectCaught(r, "DMC-RST-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RST-003"}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ STOP

TEST(MotionProof, AMotorStopAckedButIgnoredIsCaughtByStop001) {
  // ACK OK, and the motor runs on towards its far target.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::MotorStop>(m)) d.refuse = Code(AckCode::kOk);
        return d;
      },
      {}, Cases("motor/stop"));
  ExpectCaught(r, "DMC-STOP-001");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-STOP-001"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AStopAllAckedButIgnoredIsCaughtByStop002) {
  // ACK OK, and every motor runs on.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::MotorStopAll>(m)) d.refuse = Code(AckCode::kOk);
        return d;
      },
      {}, Cases("motor/stop-all"));
  ExpectCaught(r, "DMC-STOP-002");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-STOP-002"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AStopAllWithoutItsOptionalFlagsRefusedIsCaughtByStop003) {
  // ERRATA 1.7: FLAGS is optional; this device takes only the 4-byte form
  // and answers ERR_RANGE to the short one (which then stops nothing).
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* s = Is<dmc::MotorStopAll>(m); s != nullptr && !s->flags) {
          d.refuse = Code(AckCode::kErrRange);
        }
        return d;
      },
      {}, Cases("motor/stop-all"));
  ExpectCaught(r, "DMC-STOP-003");
  // The refused STOP_ALL is also one that did not stop the motors.
  const std::set<std::string> musts = FailedMusts(r);
  for (const std::string& id : musts) {
    EXPECT_TRUE(id == "DMC-STOP-003" || id == "DMC-STOP-002") << id;
  }
}

// ------------------------------------------------------------------ LIM

// The soft limits the host set for each motor, as a device that enforces them
// in its own way keeps them.
struct Limits {
  std::map<uint8_t, dmc::MotorSetLimits> by_motor;
  bool Enabled(uint8_t motor) const {
    auto it = by_motor.find(motor);
    return it != by_motor.end() && (it->second.lower_enable != 0 || it->second.upper_enable != 0);
  }
  // The refusal a move to `to` earns, when it is past an enabled limit.
  std::optional<uint16_t> Refusal(uint8_t motor, int32_t to) const {
    auto it = by_motor.find(motor);
    if (it == by_motor.end()) return std::nullopt;
    const dmc::MotorSetLimits& l = it->second;
    if (l.upper_enable != 0 && to > l.upper_limit_steps) return Code(AckCode::kErrSoftUp);
    if (l.lower_enable != 0 && to < l.lower_limit_steps) return Code(AckCode::kErrSoftLow);
    return std::nullopt;
  }
};

dmc::MotorSetLimits Disabled(dmc::MotorSetLimits l) {
  l.lower_enable = 0;
  l.upper_enable = 0;
  return l;
}

TEST(MotionProof, SwappedSoftLimitCodesAreCaughtByLim001AndLim002) {
  // The device refuses both moves past its limits, naming the other limit.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        const auto a = Decoded<dmc::Ack>(f);
        if (!a) return;
        dmc::Ack swapped = *a;
        if (a->code == Code(AckCode::kErrSoftUp)) swapped.code = Code(AckCode::kErrSoftLow);
        if (a->code == Code(AckCode::kErrSoftLow)) swapped.code = Code(AckCode::kErrSoftUp);
        raw = dmc::Encode(f.id, dmc::DeviceMessage{swapped});
      },
      Cases("limits/soft"));
  // NOTEs (no clause makes a device refuse): the other reading is noted.
  ExpectCaught(r, "DMC-LIM-001", Status::kNoted);
  ExpectCaught(r, "DMC-LIM-002", Status::kNoted);
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, AMoveRefusedAtASoftLimitThatMovesAnywayIsCaughtByLim003) {
  // The device answers ERR_SOFT_UP / ERR_SOFT_LOW but carries the move out.
  auto limits = std::make_shared<Limits>();
  const RunReport r = RunMisreading(
      [limits](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* l = Is<dmc::MotorSetLimits>(m)) {
          limits->by_motor[l->motor] = *l;
          d.instead = Disabled(*l);
        } else if (const auto* mv = Is<dmc::MotorMove>(m)) {
          if (auto code = limits->Refusal(mv->motor, mv->position_steps)) {
            d.also.push_back(*mv);
            d.refuse = *code;
          }
        }
        return d;
      },
      {}, Cases("limits/soft"));
  ExpectCaught(r, "DMC-LIM-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-LIM-003"}) << ConsoleReport(r, false);
}

TEST(MotionProof, MovesWithinEnabledSoftLimitsRefusedAreCaughtByLim004) {
  // While a motor has a soft limit enabled, the device refuses every move of
  // it with ERR_SOFT_UP.
  auto limits = std::make_shared<Limits>();
  const RunReport r = RunMisreading(
      [limits](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* l = Is<dmc::MotorSetLimits>(m)) limits->by_motor[l->motor] = *l;
        if (const auto* mv = Is<dmc::MotorMove>(m); mv != nullptr && limits->Enabled(mv->motor)) {
          d.refuse = Code(AckCode::kErrSoftUp);
        }
        return d;
      },
      {}, Cases("limits/soft"));
  ExpectCaught(r, "DMC-LIM-004");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-LIM-004"}) << ConsoleReport(r, false);
}

TEST(MotionProof, SoftLimitsEnforcedWhileDisabledAreCaughtByLim005) {
  // The device ignores the ENABLE bytes: every limit it is given is in force.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* l = Is<dmc::MotorSetLimits>(m)) {
          dmc::MotorSetLimits on = *l;
          on.lower_enable = dmc::kLimitEnabled;
          on.upper_enable = dmc::kLimitEnabled;
          d.instead = on;
        }
        return d;
      },
      {}, Cases("limits/soft"));
  ExpectCaught(r, "DMC-LIM-005");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-LIM-005"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AJogThatIgnoresTheSoftLimitsIsCaughtByLim006) {
  // The device checks its soft limits on MOTOR_MOVE only: a jog drops them.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* j = Is<dmc::MotorJog>(m)) {
          d.also.push_back(dmc::MotorSetLimits{j->motor, 0, 0, 0, 0, 0});
        }
        return d;
      },
      {}, Cases("limits/soft"));
  ExpectCaught(r, "DMC-LIM-006", Status::kNoted);  // a NOTE: no clause says how a jog meets it
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ GIO

TEST(MotionProof, ATwoByteGioInAnswerIsCaughtByGio001) {
  // ERRATA 1.6: the response carries the u32 trigger bits; here a u16.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        if (Is<dmc::GioInRequest>(req) != nullptr && f.data.size() == 4) {
          raw = Reencode(f, f.id, f.data.first(2));
        }
      },
      Cases("io/gio"));
  ExpectCaught(r, "DMC-GIO-001");
  // The cut frame fits no GIO_IN layout either (DMC-FRAME-005).
  EXPECT_EQ(FailedMusts(r), (std::set<std::string>{"DMC-FRAME-005", "DMC-GIO-001"}))
      << ConsoleReport(r, false);
}

TEST(MotionProof, AGioInBitForAnInputTheDeviceLacksIsCaughtByGio002) {
  // Input 32 reads high on a device that advertises 8 inputs.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (auto g = Decoded<dmc::GioInReport>(f)) {
          g->triggers |= 0x80000000u;
          raw = dmc::Encode(f.id, dmc::DeviceMessage{*g});
        }
      },
      Cases("io/gio"));
  ExpectCaught(r, "DMC-GIO-002");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, AGioOutWithinTheOutputsRefusedIsCaughtByGio003) {
  // GIO_OUT setting output 1 of the 8 advertised (and clearing it) refused with ERR_RANGE.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::GioOut>(m)) d.refuse = Code(AckCode::kErrRange);
        return d;
      },
      {}, Cases("io/gio"));
  ExpectCaught(r, "DMC-GIO-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-GIO-003"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AGioCamRefusedIsCaughtByGio004) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::GioCam>(m)) d.refuse = Code(AckCode::kErrUnsupported);
        return d;
      },
      {}, Cases("io/gio"));
  ExpectCaught(r, "DMC-GIO-004");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-GIO-004"}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ RT

// The failed MUST rules of `r` all among `allowed` (those the fault's own
// clause drags along).
void ExpectMustsAmong(const RunReport& r, const std::set<std::string>& allowed) {
  for (const std::string& id : FailedMusts(r)) {
    EXPECT_TRUE(allowed.count(id)) << id << " failed too\n" << ConsoleReport(r, false);
  }
}

TEST(MotionProof, UploadAxisFramesRefusedAreCaughtByRt001) {
  // The device refuses the RT_UPLOAD_MOVE_AXIS frames of a valid upload.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::RtUploadMoveAxis>(m)) d.refuse = Code(AckCode::kErrRange);
        return d;
      },
      {}, Cases("rt/upload-position"));
  ExpectCaught(r, "DMC-RT-001");
  // Without its axes the upload sends no motor to a frame.
  ExpectMustsAmong(r, {"DMC-RT-001", "DMC-RT-002", "DMC-RT-003"});
}

TEST(MotionProof, PositionFramesCountedFromOneAreCaughtByRt002) {
  // The device sends the rig to frame N - 1 for RT_POSITION_FRAME N.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* pf = Is<dmc::RtPositionFrame>(m); pf != nullptr && pf->frame > 0) {
          d.instead = dmc::RtPositionFrame{pf->frame - 1};
        }
        return d;
      },
      {}, Cases("rt/upload-position"));
  ExpectCaught(r, "DMC-RT-002");
  // Past the last set every frame holds the same positions: RT-003 holds.
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RT-002"}) << ConsoleReport(r, false);
}

TEST(MotionProof, FramesPastTheLastSetThatLeaveTheRigWhereItIsAreCaughtByRt003) {
  // "the device must repeat the final value until the end of the uploaded
  // move frame range": this one ACKs a frame past the last set and moves nothing.
  auto last_set = std::make_shared<std::optional<uint32_t>>();
  const RunReport r = RunMisreading(
      [last_set](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* a = Is<dmc::RtUploadMoveAxis>(m); a != nullptr && a->last_set) {
          *last_set = a->start_index + static_cast<uint32_t>(a->positions_steps.size()) - 1;
        }
        if (const auto* pf = Is<dmc::RtPositionFrame>(m);
            pf != nullptr && *last_set && pf->frame > **last_set) {
          d.refuse = Code(AckCode::kOk);
        }
        return d;
      },
      {}, Cases("rt/upload-position"));
  ExpectCaught(r, "DMC-RT-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RT-003"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AnRtEndSentTwiceIsCaughtByRt006) {
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (f.type == ToWire(MsgType::kRtEnd)) {
          const wire::Bytes once = raw;
          raw.insert(raw.end(), once.begin(), once.end());
        }
      },
      Cases("rt/live-run"));
  ExpectCaught(r, "DMC-RT-006");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RT-006"}) << ConsoleReport(r, false);
}

TEST(MotionProof, ALiveRunPlayedAtHalfTheFrameRateIsCaughtByRt007) {
  // The device reads FPS x 1000 as FPS x 2000: frames come every 83 ms.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* run = Is<dmc::RtRunMove>(m)) {
          dmc::RtRunMove slow = *run;
          slow.fps_x1000 /= 2;
          d.instead = slow;
        }
        return d;
      },
      {}, Cases("rt/live-run"));
  ExpectCaught(r, "DMC-RT-007");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, FrameReportsCarryingTheLastReportsPositionsAreCaughtByRt008) {
  // Each frame report is sent with the positions of the update before it:
  // the rig is reported short of the frame it has reached.
  auto prev = std::make_shared<std::optional<dmc::MotorPositionReport>>();
  const RunReport r = RunMisreading(
      {},
      [prev](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (!IsUpdate(f)) return;
        auto now = Decoded<dmc::MotorPositionReport>(f);
        if (!now) return;
        if (now->move_time_x1000 % 1000 == 0 && *prev) {
          dmc::MotorPositionReport stale = **prev;
          stale.move_time_x1000 = now->move_time_x1000;
          raw = dmc::Encode(f.id, dmc::DeviceMessage{stale});
        }
        *prev = now;
      },
      Cases("rt/live-run"));
  ExpectCaught(r, "DMC-RT-008");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, RunMoveWithoutItsOptionalFieldsRefusedIsCaughtByRt009) {
  // ERRATA 1.7: the 29-byte RT_RUN_MOVE (no FLAGS, no camera angles) refused.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* run = Is<dmc::RtRunMove>(m); run != nullptr && !run->flags) {
          d.refuse = Code(AckCode::kErrRange);
        }
        return d;
      },
      {}, Cases("rt/live-run"));
  ExpectCaught(r, "DMC-RT-009");
  // Nothing armed, nothing runs: no frame reports, no RT_END.
  ExpectMustsAmong(r, {"DMC-RT-009", "DMC-RT-004", "DMC-RT-005"});
}

TEST(MotionProof, AGoWithNothingArmedAckedOkIsCaughtByRt011) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::RtGo>(m)) d.refuse = Code(AckCode::kOk);
        return d;
      },
      {}, Cases("rt/go-unarmed"));
  ExpectCaught(r, "DMC-RT-011");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, AJogAllReportingOnlyItsDestinationIsCaughtByRt013) {
  // The frames passed on the way (1..4 of a jog to frame 5) go unreported.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (!IsUpdate(f)) return;
        const auto p = Decoded<dmc::MotorPositionReport>(f);
        if (p && p->move_time_x1000 >= 1000 && p->move_time_x1000 < 5000) {
          raw.clear();
        }
      },
      Cases("rt/jog-all"));
  ExpectCaught(r, "DMC-RT-013");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-RT-013"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AJogAllOffAFramePositionRefusedWithTheWrongCodeIsCaughtByRt014) {
  // Refused, but with ERR_RANGE where the spec names ERR_NOT_IN_POSITION.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        const auto a = Decoded<dmc::Ack>(f);
        if (Is<dmc::RtJogAll>(req) != nullptr && a && a->code == Code(AckCode::kErrNotInPosition)) {
          raw = dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{a->type, Code(AckCode::kErrRange)}});
        }
      },
      Cases("rt/jog-all"));
  ExpectCaught(r, "DMC-RT-014");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, AGoRefusedOnceTheArmedRigRestsIsCaughtByRt015) {
  // The first RT_GO after arming is answered ERR_NOT_IN_POSITION although the
  // rig is at rest; the host's retry is taken.
  auto armed = std::make_shared<bool>(false);
  const RunReport r = RunMisreading(
      [armed](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::RtRunMove>(m) || Is<dmc::RtShootFrame>(m) || Is<dmc::RtShootFrame2>(m)) {
          *armed = true;
        }
        if (Is<dmc::RtGo>(m) && *armed) {
          *armed = false;
          d.refuse = Code(AckCode::kErrNotInPosition);
        }
        return d;
      },
      {}, Cases("rt/live-run"));
  ExpectCaught(r, "DMC-RT-015");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------------ VIRT

// The DMC-16 with virtual axes (boom-swing-track, aim point).
std::string VirtualProfile() {
  const char* d = std::getenv("MOCO_SOURCE_DIR");
  return std::string(d != nullptr ? d : ".") + "/fixtures/profiles/dmc16-virtual.json";
}

TEST(MotionProof, AVirtPositionAnswerOneByteShortIsCaughtByVirt001) {
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        if (Is<dmc::VirtGetPositionRequest>(req) != nullptr && !f.data.empty() &&
            f.type == ToWire(MsgType::kVirtGetPosition)) {
          raw = Reencode(f, f.id, f.data.first(f.data.size() - 1));
        }
      },
      Cases("virtual/get-position"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-001");
  // The cut frame fits no VIRT_GET_POSITION layout either (DMC-FRAME-005).
  EXPECT_EQ(FailedMusts(r), (std::set<std::string>{"DMC-FRAME-005", "DMC-VIRT-001"}))
      << ConsoleReport(r, false);
}

TEST(MotionProof, AVirtConfigWithItsCompensationTableRefusedIsCaughtByVirt002) {
  // ERRATA 1.7: the table is optional, and so is taking it; refusing it is not.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* c = Is<dmc::VirtConfig>(m)) {
          const auto* b = std::get_if<dmc::VirtRigBoomSwingTrack>(&c->rig);
          if (b != nullptr && b->compensation) d.refuse = Code(AckCode::kErrRange);
        }
        return d;
      },
      {}, Cases("virtual/config"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-002");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-VIRT-002"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AVirtualMoveThatStopsShortIsCaughtByVirt003) {
  // Every virtual target is reached 0.05 (units or degrees) short.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* v = Is<dmc::VirtMove>(m); v != nullptr && v->axis >= 1 && v->axis <= 6) {
          d.instead = dmc::VirtMove{v->axis, v->position_x100000 - 5000};
        }
        return d;
      },
      {}, Cases("virtual/move"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-VIRT-003"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AnUnreachableVirtualMoveThatStartsTheTrackIsCaughtByVirt004) {
  // Sent 6 units above a boom of 2, the device refuses, but only after it
  // has set the track motor (motor 3) going.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* v = Is<dmc::VirtMove>(m);
            v != nullptr && v->axis == 3 && v->position_x100000 > 500000) {
          d.also.push_back(dmc::MotorMove{3, 50000});
        }
        return d;
      },
      {}, Cases("virtual/move"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-004");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-VIRT-004"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AnUnreachableVirtualTargetRefusedWithErrGeneralIsCaughtByVirt005) {
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        const auto* v = Is<dmc::VirtMove>(req);
        const auto a = Decoded<dmc::Ack>(f);
        if (v != nullptr && v->axis >= 1 && v->axis <= 6 && a &&
            a->code == Code(AckCode::kErrRange)) {
          raw =
              dmc::Encode(f.id, dmc::DeviceMessage{dmc::Ack{a->type, Code(AckCode::kErrGeneral)}});
        }
      },
      Cases("virtual/move"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-005");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, VirtualMotorZeroAcceptedIsCaughtByVirt006) {
  // The device numbers its virtual axes from 0: VIRT_MOVE and VIRT_STOP of
  // axis 0 are ACKed OK.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        const auto* mv = Is<dmc::VirtMove>(m);
        const auto* st = Is<dmc::VirtStop>(m);
        if ((mv != nullptr && mv->axis == 0) || (st != nullptr && st->axis == 0)) {
          d.refuse = Code(AckCode::kOk);
        }
        return d;
      },
      {}, Cases("virtual/move"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-006");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, AVirtStopAckedButIgnoredIsCaughtByVirt007) {
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (Is<dmc::VirtStop>(m)) d.refuse = Code(AckCode::kOk);
        return d;
      },
      {}, Cases("virtual/stop"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-007");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-VIRT-007"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AJogOnLineThatIgnoresSpeedZeroIsCaughtByVirt008) {
  // VIRT_JOG_ON_LINE speed 0 is ACKed OK and the rig goes on along the line.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* j = Is<dmc::VirtJogOnLine>(m); j != nullptr && j->speed == 0) {
          d.refuse = Code(AckCode::kOk);
        }
        return d;
      },
      {}, Cases("virtual/jog"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-008");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-VIRT-008"}) << ConsoleReport(r, false);
}

TEST(MotionProof, AnAimPointEchoedWithAnotherZIsCaughtByVirt009) {
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        if (Is<dmc::VirtAimPoint>(req) == nullptr) return;
        if (auto a = Decoded<dmc::VirtAimPoint>(f)) {
          a->z_x1000 += 1;
          raw = dmc::Encode(f.id, dmc::DeviceMessage{*a});
        }
      },
      Cases("virtual/aim-point"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-009");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-VIRT-009"}) << ConsoleReport(r, false);
}

TEST(MotionProof, VirtPositionAimFieldsOffTheAimPointAreCaughtByVirt010) {
  // VIRT_GET_POSITION reports aim-x a thousandth off the aim point in force.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        auto p = Decoded<dmc::VirtPositionReport>(f);
        if (p && p->aim) {
          p->aim->x_x1000 += 1;
          raw = dmc::Encode(f.id, dmc::DeviceMessage{*p});
        }
      },
      Cases("virtual/aim-point"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-010");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(MotionProof, OnlyTheBoomSwingTrackBitAdvertisedIsCaughtByVirt011) {
  // HI advertises boom-swing-track (0x0004) without the other three modes.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        if (auto hi = Decoded<dmc::HiResponse>(f)) {
          hi->capabilities &=
              ~(dmc::kCapVirtSwingPan | dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz);
          raw = dmc::Encode(f.id, dmc::DeviceMessage{*hi});
        }
      },
      Cases("virtual/config"), VirtualProfile());
  ExpectCaught(r, "DMC-VIRT-011");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

// ------------------------------------------------------------ attribution
// A fault in one clause fails the rule of that clause and few others, over
// the whole suite (issue: a stale MOTOR_STATUS used to fail 22 rules).

// The SHOULD rules a run failed.
std::set<std::string> FailedShoulds(const RunReport& r) {
  std::set<std::string> out;
  for (const auto& [id, s] : r.rules) {
    const Rule* rule = FindRule(id);
    if (s.status == Status::kFail && rule != nullptr && rule->level == Level::kShould) {
      out.insert(id);
    }
  }
  return out;
}

TEST(Attribution, AMotorStatusThatNeverShowsMotionFailsStat004AndNothingElse) {
  // "MOTOR STATUS ... bit set = motor moving": every answer says nothing moves.
  // The host believes a status of rest only when the position updates have
  // stopped changing, so the cases go on to judge the motion itself.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage*, wire::Bytes& raw) {
        // The motor bits only: the DMX STATUS byte stays the device's.
        if (const auto st = Decoded<dmc::MotorStatusResponse>(f)) {
          raw =
              dmc::Encode(f.id, dmc::DeviceMessage{dmc::MotorStatusResponse{0, st->dmx_adjusting}});
        }
      },
      RunOptions{});
  ExpectCaught(r, "DMC-STAT-004");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-STAT-004"}) << ConsoleReport(r, false);
  EXPECT_EQ(FailedShoulds(r), std::set<std::string>{}) << ConsoleReport(r, false);
}

TEST(Attribution, APositionAnswerOneStepOffOverTheWholeSuiteFailsFewRules) {
  // Every answer to MOTOR_GET_POSITION reports motor 1 a step past where it
  // is; the updates report it right.
  const RunReport r = RunMisreading(
      {},
      [](const dmc::FrameRef& f, const dmc::HostMessage* req, wire::Bytes& raw) {
        if (Is<dmc::MotorGetPositionRequest>(req) == nullptr) return;
        auto p = Decoded<dmc::MotorPositionReport>(f);
        if (!p || p->positions_steps.empty()) return;
        p->positions_steps[0] += 1;
        raw = dmc::Encode(f.id, dmc::DeviceMessage{*p});
      },
      RunOptions{});
  ExpectCaught(r, "DMC-POS-006");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-POS-006"}) << ConsoleReport(r, false);
}

TEST(Attribution, AMotorThatStopsAStepShortOverTheWholeSuiteFailsMove003) {
  // Every MOTOR_MOVE ends one step short of its target.
  const RunReport r = RunMisreading(
      [](const dmc::HostMessage& m) {
        Reading d;
        if (const auto* mv = Is<dmc::MotorMove>(m)) {
          d.instead = dmc::MotorMove{mv->motor, mv->position_steps - 1};
        }
        return d;
      },
      {}, RunOptions{});
  ExpectCaught(r, "DMC-MOVE-003");
  EXPECT_EQ(FailedMusts(r), std::set<std::string>{"DMC-MOVE-003"}) << ConsoleReport(r, false);
}

}  // namespace
}  // namespace moco::conformance
