// DMC v2 for the runner (see dmc_protocol.h).
#include "conformance/protocols/dmc/dmc_protocol.h"

#include <cstdio>
#include <string>

#include "base/format.h"
#include "wire/dmc_frame.h"

namespace moco::conformance {

bool Applies(Needs needs, const dmc::HiResponse& hi) {
  constexpr uint32_t kVirtualCaps = dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                                    dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz;
  switch (needs) {
    case Needs::kNothing:
      return true;
    case Needs::kMotors:
      return hi.motor_count >= 1;
    case Needs::kTwoMotors:
      return hi.motor_count >= 2;
    case Needs::kDmx:
      return hi.dmx_count >= 1;
    case Needs::kGioOut:
      return hi.gio_out_count >= 1;
    case Needs::kGioIn:
      return hi.gio_in_count >= 1;
    case Needs::kRealTime:
      return (hi.capabilities & dmc::kCapRealTime) != 0 && hi.motor_count >= 1;
    case Needs::kGoMotion:
      return (hi.capabilities & dmc::kCapGoMotion) != 0 && hi.motor_count >= 1;
    case Needs::kGoMotion2:
      return (hi.capabilities & dmc::kCapGoMotion2) != 0 && hi.motor_count >= 1;
    case Needs::kLooping:
      return (hi.capabilities & dmc::kCapRtLooping) != 0;
    case Needs::kVirtual:
      return (hi.capabilities & kVirtualCaps) != 0;
    case Needs::kNoVirtual:
      return (hi.capabilities & kVirtualCaps) == 0;
    case Needs::kVirtualBoomRig:
      return (hi.capabilities & dmc::kCapVirtBoomSwingTrack) != 0 && hi.motor_count >= 6;
    case Needs::kAimPoint:
      return (hi.capabilities & dmc::kCapAimPoint) != 0;
    case Needs::kSsThreeAxes:
      return false;  // a StackShot need: no DMC v2 device has it
    default:         // another protocol's needs
      return false;
  }
  return false;
}

std::optional<dmc::HiResponse> DmcProtocol::Discover(DmcHost& probe) {
  if (const auto* hi = As<dmc::HiResponse>(probe.Call(dmc::HiRequest{}))) return *hi;
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

std::optional<dmc::HiResponse> DmcProtocol::Greet(DmcHost& host, Target& /*target*/,
                                                  const dmc::HiResponse& /*discovered*/) {
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
