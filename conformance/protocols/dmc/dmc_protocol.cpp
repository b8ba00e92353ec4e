// DMC v2 for the runner (see dmc_protocol.h).
#include "conformance/protocols/dmc/dmc_protocol.h"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <string>

#include "base/format.h"
#include "conformance/protocols/dmc/dmc_timing.h"
#include "wire/dmc_frame.h"

namespace moco::conformance {

namespace {

using Hi = dmc::HiResponse;

constexpr uint32_t kVirtualCaps = dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                                  dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz;

constexpr bool Has(const Hi& hi, uint32_t capability) {
  return (hi.capabilities & capability) != 0;
}
constexpr bool RealTime(const Hi& hi) { return Has(hi, dmc::kCapRealTime) && hi.motor_count >= 1; }

// What HI must say for each of DmcNeeds.
struct NeedTest {
  Need need;
  bool (*met)(const Hi& hi);
};
using N = DmcNeeds;
constexpr NeedTest kNeedTests[] = {
    {N::kMotors, [](const Hi& hi) { return hi.motor_count >= 1; }},
    {N::kTwoMotors, [](const Hi& hi) { return hi.motor_count >= 2; }},
    {N::kDmx, [](const Hi& hi) { return hi.dmx_count >= 1; }},
    {N::kGioOut, [](const Hi& hi) { return hi.gio_out_count >= 1; }},
    {N::kGioIn, [](const Hi& hi) { return hi.gio_in_count >= 1; }},
    {N::kHwLimits, [](const Hi& hi) { return hi.hw_limit_count >= 1 && hi.motor_count >= 1; }},
    {N::kRealTime, [](const Hi& hi) { return RealTime(hi); }},
    {N::kGoMotion, [](const Hi& hi) { return Has(hi, dmc::kCapGoMotion) && hi.motor_count >= 1; }},
    {N::kGoMotion2,
     [](const Hi& hi) { return Has(hi, dmc::kCapGoMotion2) && hi.motor_count >= 1; }},
    {N::kLooping, [](const Hi& hi) { return Has(hi, dmc::kCapRtLooping); }},
    {N::kVirtual, [](const Hi& hi) { return Has(hi, kVirtualCaps); }},
    {N::kNoVirtual, [](const Hi& hi) { return !Has(hi, kVirtualCaps); }},
    {N::kVirtualBoomRig,
     [](const Hi& hi) { return Has(hi, dmc::kCapVirtBoomSwingTrack) && hi.motor_count >= 6; }},
    {N::kAimPoint, [](const Hi& hi) { return Has(hi, dmc::kCapAimPoint); }},
    {N::kCoupleMotors,
     [](const Hi& hi) { return Has(hi, dmc::kCapCoupleMotors) && hi.motor_count >= 2; }},
    {N::kRtDmx, [](const Hi& hi) { return RealTime(hi) && hi.dmx_count >= 1; }},
    {N::kRtTriggers, [](const Hi& hi) { return RealTime(hi) && hi.gio_out_count >= 1; }},
    {N::kRtCamera, [](const Hi& hi) { return RealTime(hi) && Has(hi, dmc::kCapRtCameraTrigger); }},
};
static_assert(std::size(kNeedTests) == std::size(N::kOwn), "a DMC need without its test");

}  // namespace

bool Applies(const Need& needs, const dmc::HiResponse& hi) {
  if (needs == N::kNothing) return true;
  for (const NeedTest& t : kNeedTests) {
    if (t.need == needs) return t.met(hi);
  }
  return false;  // another protocol's need
}

std::optional<dmc::HiResponse> DmcProtocol::Discover(DmcHost& probe) {
  // Asked twice, as a host does after its answer timeout: a device that
  // missed the first HI (DMC-HI-016) is still judged on everything else.
  for (int attempt = 0; attempt < 2 && !probe.link_lost(); ++attempt) {
    if (const auto* hi = As<dmc::HiResponse>(probe.Call(dmc::HiRequest{}))) return *hi;
  }
  return std::nullopt;
}

void DmcProtocol::Describe(const dmc::HiResponse& h, RunReport& report) {
  const std::string caps = base::Hex(h.capabilities, 4);
  const std::string fw = std::to_string(h.fw_major) + "." + std::to_string(h.fw_minor) + "." +
                         std::to_string(h.fw_rev);
  report.device = "\"" + h.NameText() + "\" fw " + fw + ", " + std::to_string(h.motor_count) +
                  " motors, " + std::to_string(h.dmx_count) + " DMX, GIO " +
                  std::to_string(h.gio_out_count) + " out / " + std::to_string(h.gio_in_count) +
                  " in, capabilities " + caps;
  report.device_info = {{"name", h.NameText()},
                        {"firmware", fw},
                        {"motor_count", h.motor_count},
                        {"dmx_count", h.dmx_count},
                        {"gio_out_count", h.gio_out_count},
                        {"gio_in_count", h.gio_in_count},
                        {"hw_limit_count", h.hw_limit_count},
                        {"upload_frame_count", h.upload_frame_count},
                        {"capabilities", h.capabilities}};
}

namespace {

using dmc_cases::kRestPollNs;
using dmc_cases::kSettleBusyRetryNs;
using dmc_cases::kSettleBusyWaitNs;
using dmc_cases::kSettleFlushNs;
using dmc_cases::kSettleHiAnswerNs;
using dmc_cases::kSettleMotionWaitNs;

// Brings a device that introduced itself back to a known state before a case,
// as Dragonframe prepares a rig, without judging anything (a case is judged
// on its own traffic, not on what an earlier case left behind):
// - a frame an earlier case left unfinished (a header declaring a Length the
//   device waits for: a 2048-byte buffer legitimately waits for 2002 bytes)
//   is completed by a flush past the largest buffer any device may have,
//   when a HI goes unanswered;
// - motion left over is waited out (bounded);
// - the motors the cases move are enabled with MOTOR_CONFIGURE (devices
//   that start with motors disabled ignore moves until then), retried while
//   the device refuses commands for a while after a stop.
void Settle(DmcHost& host, const dmc::HiResponse& device) {
  MutedVerdicts mute(host.verdicts());
  if (host.Await(host.Send(dmc::HiRequest{}), kSettleHiAnswerNs) == nullptr && !host.link_lost()) {
    static const wire::Bytes kFlush(4096, 0x00);
    host.SendNoise(kFlush);
    host.Idle(kSettleFlushNs);
    if (host.Call(dmc::HiRequest{}) == nullptr) return;  // the greeting judges the silence
  }
  if (device.motor_count == 0) return;
  const TimeNs until = host.Now() + kSettleMotionWaitNs;
  for (;;) {
    const auto* st = As<dmc::MotorStatusResponse>(host.Call(dmc::MotorStatusRequest{}));
    if (st == nullptr || st->moving_bits == 0 || host.Now() >= until || host.link_lost()) break;
    host.Idle(kRestPollNs);
  }
  // Motors 1..8 cover every case (the boom rig's six included).
  const uint8_t motors = std::min<uint8_t>(device.motor_count, 8);
  const TimeNs busy_until = host.Now() + kSettleBusyWaitNs;
  for (uint8_t m = 1; m <= motors; ++m) {
    for (;;) {
      // Enabled, with the blur flag go-motion needs (a DMC-16's power-on flags).
      const DmcRecord* r =
          host.Call(dmc::MotorConfigure{m, dmc::kMotorEnabled | dmc::kMotorBlurEnabled});
      const std::optional<uint32_t> code = AckCodeOf(r);
      const bool busy = code && (*code == dmc::ToWire(dmc::AckCode::kErrHardLow) ||
                                 *code == dmc::ToWire(dmc::AckCode::kErrMoving));
      if (!busy || host.Now() >= busy_until || host.link_lost()) break;
      host.Idle(kSettleBusyRetryNs);
    }
  }
}

}  // namespace

std::optional<dmc::HiResponse> DmcProtocol::Greet(DmcHost& host, Target& /*target*/,
                                                  const dmc::HiResponse& discovered) {
  // A device that never introduced itself (an empty HI) is greeted only.
  if (discovered.motor_count > 0 || discovered.NameText() != "") Settle(host, discovered);
  if (const auto* seen = As<dmc::HiResponse>(host.Call(dmc::HiRequest{}))) return *seen;
  return std::nullopt;
}

PositionSeries DmcProtocol::Positions(const std::vector<Chunk>& traffic) {
  PositionSeries s;
  dmc::FrameDecoder dec;
  for (const Chunk& c : traffic) {
    if (c.from_host) continue;
    dec.Feed(c.bytes, [&](const dmc::FrameEvent& e) {
      const auto* f = std::get_if<dmc::FrameRef>(&e);
      if (f == nullptr || f->type != dmc::ToWire(dmc::MsgType::kMotorGetPosition)) return;
      auto m = dmc::DecodeDeviceMessage(f->type, f->data);
      if (!m.ok()) return;
      const auto* p = std::get_if<dmc::MotorPositionReport>(&m.value());
      if (p == nullptr) return;
      for (size_t i = 0; i < p->positions_steps.size(); ++i) {
        s[static_cast<int>(i + 1)].emplace_back(c.t_ns, p->positions_steps[i]);
      }
    });
  }
  return s;
}

}  // namespace moco::conformance
