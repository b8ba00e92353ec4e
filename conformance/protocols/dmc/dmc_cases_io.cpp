// DMC v2 general I/O and DMX cases (dmc-v2-protocol.txt "MSG_GIO_IN", "MSG_GIO_OUT",
// "MSG_GIO_CAM", "MSG_DMX", "MSG_MOTOR_STATUS"): GIO_IN, GIO_OUT and GIO_CAM, DMX
// levels with a ramp and its DMX STATUS, and the unsolicited GIO_IN when an input
// changes, each judged against the named rules. Listed by the table in dmc_cases.cpp.
#include <string>

#include "conformance/protocols/dmc/dmc_cases_internal.h"

namespace moco::conformance::dmc_cases {

using dmc::AckCode;
using dmc::MsgType;

// ---------------------------------------------------------------- io

void Io(DmcCaseContext& c) {
  DmcHost& h = c.host;
  if (As<dmc::GioInReport>(h.Call(dmc::GioInRequest{})) == nullptr) {
    c.v.NotExercised("DMC-GIO-002",
                     "the device answered GIO_IN without its inputs (DMC-GIO-001), so no TRIGGERS "
                     "bits could be judged");
  }
  if (c.device.gio_out_count > 0) ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{1}));
  if (c.device.gio_out_count > 0) ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{0}));
  ExpectOk(c, "DMC-GIO-004", h.Call(dmc::GioCam{dmc::kGioCamShutter}));
  ExpectOk(c, "DMC-GIO-004", h.Call(dmc::GioCam{0}));
}

void Dmx(DmcCaseContext& c) {
  DmcHost& h = c.host;
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {10, 20, 30}}));
  ExpectCode(c, "DMC-ERR-011", h.Call(dmc::Dmx{0, 0, {10}}), AckCode::kErrRange);
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {0, 0, 0}}));
  // MSG_DMX "If RAMP is set to 1, the device should ramp the light value ...
  // rather than switching to it immediately"; MSG_MOTOR_STATUS "DMX STATUS
  // BYTE 1=DMX adjusting, 0=Not adjusting". Channel 1 ramps over its full range.
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{1, 1, {255}}));
  const DmcRecord* r = h.Call(dmc::MotorStatusRequest{});
  const auto* st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-DMX-002", st != nullptr && st->dmx_adjusting == 1, [&] {
    return EvOf(h, r, "MOTOR_STATUS with DMX STATUS 1 right after a ramp to 255 began", Show(r));
  });
  // The ramp ends: polled as a host waiting for the rig to settle would.
  const TimeNs until = h.Now() + kDmxRampEndWithinNs;
  for (;;) {
    r = h.Call(dmc::MotorStatusRequest{});
    st = As<dmc::MotorStatusResponse>(r);
    if (st == nullptr || st->dmx_adjusting == 0 || h.Now() >= until) break;
    h.Idle(kDmxRampPollNs);
  }
  c.v.Check("DMC-DMX-003", st != nullptr && st->dmx_adjusting == 0, [&] {
    return EvOf(h, r, "MOTOR_STATUS with DMX STATUS 0 within 30 s of the ramp", Show(r));
  });
  // "RAMP BYTE 1=ramp, 0=immediate": back to 0 at once.
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, {0}}));
  r = h.Call(dmc::MotorStatusRequest{});
  st = As<dmc::MotorStatusResponse>(r);
  c.v.Check("DMC-DMX-004", st != nullptr && st->dmx_adjusting == 0, [&] {
    return EvOf(h, r, "MOTOR_STATUS with DMX STATUS 0 right after an immediate set", Show(r));
  });
}

// A general I/O input changing (in-process: the runner drives it): "The
// device should also send this message, unsolicited, any time the inputs
// change" (MSG_GIO_IN), after its debounce.
void GioInputChange(DmcCaseContext& c) {
  DmcHost& h = c.host;
  for (const bool level : {true, false}) {
    const size_t mark = h.records().size();
    if (!c.target.SetGioInput(0, level)) {
      c.log.push_back(
          "the target has no input the runner can drive: GIO_IN on change not exercised");
      c.v.NotExercised("DMC-GIO-005",
                       "the target has no input the runner can drive (in-process targets do)");
      return;
    }
    const int i = h.WaitFor(mark, kGioInChangeWithinNs,
                            [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kGioIn); });
    const DmcRecord* g = i >= 0 ? &h.records()[static_cast<size_t>(i)] : nullptr;
    const auto* in = As<dmc::GioInReport>(g);
    Expect(c, "DMC-GIO-005", in != nullptr && ((in->triggers & 1u) != 0) == level,
           std::string("an unsolicited GIO_IN with input 1 ") + (level ? "set" : "clear") +
               " within 1 s of the change",
           Show(g));
  }
}

}  // namespace moco::conformance::dmc_cases
