// DMC v2 real-time, go-motion, looping and virtual-axis cases
// (dmc-v2-protocol.txt "MSG_RT_*", "MSG_VIRT_*", "Capabilities"; ERRATA
// 1.5-1.11): uploads, live runs, jogs to a frame, shooting and the virtual
// rig, judged against the named rules. Listed by the table in dmc_cases.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "base/format.h"
#include "conformance/protocols/dmc/dmc_cases_internal.h"

namespace moco::conformance::dmc_cases {

using dmc::AckCode;
using dmc::MsgType;
using dmc::ToWire;

// ---------------------------------------------------------------- real-time

// Uploads frames 0..20 (fewer when the device holds fewer: HI UPLOAD FRAME
// COUNT): motor 1 climbs 40 steps a frame and motor 2 falls 25 a frame over
// frames 0..10 (last set), then both hold. `more` sends further sections
// (DMX, triggers) before UPLOAD_MOVE_END.
std::optional<Uploaded> Upload(DmcCaseContext& c, const std::function<void(uint32_t end)>& more) {
  DmcHost& h = c.host;
  const auto p0 = GetPositions(h);
  if (!p0) return std::nullopt;
  Uploaded u;
  u.end = std::min<uint32_t>(20, std::max<uint32_t>(c.device.upload_frame_count, 2) - 1);
  const uint8_t motors = std::min<uint8_t>(c.device.motor_count, 2);
  ExpectOk(c, "DMC-RT-001", h.Call(dmc::RtUploadMoveBegin{0, u.end}));
  for (uint8_t m = 1; m <= motors; ++m) {
    const int32_t step = m == 1 ? 40 : -25;
    std::vector<int32_t> section;
    const int last = static_cast<int>(std::min<uint32_t>(10, u.end));
    for (int k = 0; k <= last; ++k) section.push_back(At(*p0, m - 1u) + step * k);
    ExpectOk(c, "DMC-RT-001", h.Call(dmc::RtUploadMoveAxis{m, 0, true, section}));
    std::vector<int32_t> path = section;
    while (path.size() <= u.end) path.push_back(section.back());
    u.path.push_back(path);
  }
  if (more) more(u.end);
  ExpectOk(c, "DMC-RT-001", h.Call(dmc::RtUploadMoveEnd{}));
  return u;
}

// Judges reported positions `p` against frame `frame`'s uploaded `want`:
// `rule` takes a step either way (a device whose position is a float it
// truncates reads 199 for 200: FACTS DMC v2, the reference firmware), and
// DMC-RT-016 (NOTE) notes any position that is not exact.
bool OnFramePositions(DmcCaseContext& c, std::string_view rule,
                      const std::optional<std::vector<int32_t>>& p,
                      const std::vector<int32_t>& want, uint32_t frame) {
  bool near = p.has_value(), exact = p.has_value();
  for (size_t i = 0; p && i < want.size(); ++i) {
    const int64_t d = static_cast<int64_t>(At(*p, i)) - want[i];
    near = near && d >= -1 && d <= 1;
    exact = exact && d == 0;
  }
  const std::string expected = "frame " + std::to_string(frame) + " positions " + Vec(want);
  const std::string observed = p ? Vec(*p) : "no position";
  if (near) Expect(c, "DMC-RT-016", exact, expected, observed);
  return Expect(c, rule, near, expected + " (within a step)", observed);
}

bool AtFrame(DmcCaseContext& c, const Uploaded& u, uint32_t frame, std::string_view rule) {
  ExpectOk(c, rule, c.host.Call(dmc::RtPositionFrame{frame}));
  WaitRest(c, kRestWaitNs);
  const auto p = GetPositions(c.host);
  std::vector<int32_t> want;
  for (const auto& path : u.path) want.push_back(path[frame]);
  return OnFramePositions(c, rule, p, want, frame);
}

void UploadPosition(DmcCaseContext& c) {
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, std::min<uint32_t>(5, u->end), "DMC-RT-002");
  AtFrame(c, *u, std::min<uint32_t>(15, u->end), "DMC-RT-003");
  ExpectRefused(c, "DMC-RT-010", c.host.Call(dmc::RtPositionFrame{u->end + 1}));
  AtFrame(c, *u, 0, "DMC-RT-002");
}

dmc::RtRunMove ShortRun(uint32_t end) {
  dmc::RtRunMove run;
  run.fps_x1000 = kRunFps * dmc::kFpsScale;
  run.start_frame = 0;
  run.end_frame = end;
  run.preroll_ms = kShortRunRollMs;
  run.postroll_ms = kShortRunRollMs;
  return run;  // FLAGS and the camera angles left out: 29 data bytes
}

void LiveRun(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  const uint32_t end = std::min<uint32_t>(10, u->end);
  ExpectOk(c, "DMC-RT-009", h.Call(ShortRun(end)));
  WaitRest(c, kRestWaitNs);
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-RT-009", Go(c));
  const int e = h.WaitFor(mark, kRunEndWaitNs,
                          [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  Expect(c, "DMC-RT-005", e >= 0, "RT_END after the run", "none within 20 s");
  h.Idle(kSecondRtEndWatchNs);
  const int ends = CountSince(h, mark, MsgType::kRtEnd);
  Expect(c, "DMC-RT-006", ends <= 1, "one RT_END", std::to_string(ends) + " RT_END messages");
  const std::vector<Update> ups = UpdatesSince(h, mark);
  const double interval_ns = static_cast<double>(sim::kNsPerSecond) / kRunFps;
  const TimeNs slack = c.target.VirtualClock() ? 0 : kFrameReportSlackNs;
  TimeNs prev_t = -1;  // none yet
  // Whether an update has every motor within frame k's interval of the path.
  auto on_frame = [&](const Update& up, uint32_t k) {
    for (size_t m = 0; m < u->path.size(); ++m) {
      const int32_t a = u->path[m][k], b = u->path[m][std::min(k + 1, u->end)];
      const int32_t p = At(up.positions, m);
      if (p < std::min(a, b) || p > std::max(a, b)) return false;
    }
    return true;
  };
  for (uint32_t k = 0; k <= end; ++k) {
    // The frame's report: the first update carrying frame k's MOVE TIME with
    // the rig at that frame. The periodic updates ("about every 0.10
    // seconds") go on beside the frame reports, and a device may give the
    // pre-roll's and post-roll's updates the start or end frame's MOVE TIME
    // (docs/protocol-notes.md "Live-move reports").
    const Update* first = nullptr;
    for (const Update& up : ups) {
      if (up.move_time / 1000 == k && on_frame(up, k)) {
        first = &up;
        break;
      }
    }
    for (size_t i = 0; first == nullptr && i < ups.size(); ++i) {
      if (ups[i].move_time / 1000 == k) first = &ups[i];
    }
    if (!Expect(c, "DMC-RT-004", first != nullptr,
                "a report with MOVE TIME " + std::to_string(k * 1000),
                "none for frame " + std::to_string(k))) {
      prev_t = -1;
      continue;
    }
    // Timed from frame 1 on: a device may give the pre-roll's updates the
    // start frame's MOVE TIME (FACTS DMC v2), so when frame 0 was reached is
    // not known from its reports.
    if (prev_t >= 0 && k >= 2) {
      const TimeNs dt = first->t_ns - prev_t;
      c.v.Check("DMC-RT-007",
                dt >= static_cast<TimeNs>(interval_ns * 0.5) - slack &&
                    dt <= static_cast<TimeNs>(interval_ns * 1.5) + slack,
                [&] {
                  return EvOf(h, first->rec, "about 41.7 ms after the previous frame's report",
                              std::to_string(dt / kMs) + " ms");
                });
    }
    prev_t = first->t_ns;
    for (size_t m = 0; m < u->path.size(); ++m) {
      const int32_t a = u->path[m][k], b = u->path[m][std::min(k + 1, u->end)];
      const int32_t p = At(first->positions, m);
      c.v.Check("DMC-RT-008", p >= std::min(a, b) && p <= std::max(a, b), [&] {
        return EvOf(h, first->rec,
                    "motor " + std::to_string(m + 1) + " within [" +
                        std::to_string(std::min(a, b)) + ", " + std::to_string(std::max(a, b)) +
                        "] at frame " + std::to_string(k),
                    std::to_string(p));
      });
    }
  }
  WaitRest(c, kRestWaitNs);
}

void StopRun(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  h.Call(ShortRun(10));
  WaitRest(c, kRestWaitNs);
  const size_t mark = h.records().size();
  Go(c);
  h.WaitFor(mark, kRunFrameWaitNs, [](const DmcRecord& r) {
    const auto* p = As<dmc::MotorPositionReport>(&r);
    return r.request < 0 && p != nullptr && p->move_time_x1000 >= 3000;
  });
  const size_t stop_mark = h.records().size();
  ExpectOk(c, "DMC-STOP-002", h.Call(dmc::MotorStopAll{}));
  const int e = h.WaitFor(stop_mark, kStopRunEndWithinNs,
                          [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  Expect(c, "DMC-RT-012", e >= 0, "RT_END after STOP_ALL ends the run", "none within 5 s");
  WaitRest(c, kRestWaitNs);
}

void GoUnarmed(DmcCaseContext& c) { ExpectRefused(c, "DMC-RT-011", c.host.Call(dmc::RtGo{})); }

void JogAll(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  const uint32_t to = std::min<uint32_t>(5, u->end);
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-RT-013", h.Call(dmc::RtJogAll{24000, to}));
  WaitRest(c, kRestWaitNs);
  h.Idle(kJogAllLateReportsNs);
  const std::vector<Update> ups = UpdatesSince(h, mark);
  for (uint32_t k = 1; k <= to; ++k) {
    bool seen = false;
    for (const Update& up : ups) seen = seen || up.move_time / 1000 == k;
    Expect(c, "DMC-RT-013", seen, "a report with MOVE TIME " + std::to_string(k * 1000),
           "none for frame " + std::to_string(k));
  }
  const auto p = GetPositions(h);
  if (!p) return;
  // "Jog all motors towards the destination frame": the rig ends on it.
  std::vector<int32_t> want;
  for (const auto& path : u->path) want.push_back(path[to]);
  OnFramePositions(c, "DMC-RT-013", p, want, to);
  MoveAndRest(c, 1, At(*p, 0) + 37);
  ExpectCode(c, "DMC-RT-014", h.Call(dmc::RtJogAll{24000, 0}), AckCode::kErrNotInPosition);
  MoveAndRest(c, 1, u->path[0][0]);
}

void Shoot(DmcCaseContext& c, bool second) {
  DmcHost& h = c.host;
  const std::string_view rule = second ? "DMC-GM-002" : "DMC-GM-001";
  const auto u = Upload(c);
  if (!u) return;
  const uint32_t frame = std::min<uint32_t>(3, u->end);
  AtFrame(c, *u, frame, "DMC-RT-002");
  const int32_t at = u->path[0][frame];
  const std::vector<dmc::BlurMotor> blur = {{1, at - 20, at + 20}};
  if (second) {
    ExpectOk(c, rule, h.Call(dmc::RtShootFrame2{frame, kShootExposureMs, 90, 270, blur}));
  } else {
    ExpectOk(c, rule,
             h.Call(dmc::RtShootFrame{frame, dmc::kDirectionForward, kShootExposureMs, 500, blur}));
  }
  WaitRest(c, kRestWaitNs);
  const auto before = GetPositions(h);
  const size_t mark = h.records().size();
  const DmcRecord* go = Go(c);
  ExpectOk(c, rule, go);
  const int e = h.WaitFor(mark, kShootEndWaitNs,
                          [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  Expect(c, rule, e >= 0, "RT_END after the exposure", "none within 10 s");
  if (e >= 0 && go != nullptr) {
    // The exposure is 200 ms: an RT_END sooner than that ended no exposure.
    const TimeNs took = h.records()[static_cast<size_t>(e)].t_ns - go->t_ns;
    Expect(c, rule, took >= kShootExposureNs, "RT_END at least 200 ms (the exposure) after GO",
           "RT_END " + std::to_string(took / kMs) + " ms after GO");
  }
  WaitRest(c, kRestWaitNs);
  // The blurred motor sweeps its 40-step blur range while the shutter is open.
  const auto after = GetPositions(h);
  if (before && after) {
    const int32_t moved = std::abs(At(*after, 0) - At(*before, 0));
    Expect(c, rule, moved >= 20, "motor 1 moved through its blur range (40 steps)",
           "motor 1 moved " + std::to_string(moved) + " step(s)");
  }
}

// A ping-pong run of frames 0..10 at 24 fps; once its second pass (back
// towards frame 0) is under way, STOP_LOOP: "The currently running
// loop/ping-pong must stop after it reaches the next end point", frame 0.
void StopLoop(DmcCaseContext& c) {
  DmcHost& h = c.host;
  if (c.device.motor_count == 0 || (c.device.capabilities & dmc::kCapRealTime) == 0) {
    ExpectOk(c, "DMC-LOOP-001", h.Call(dmc::RtStopLoop{}));
    return;
  }
  const auto u = Upload(c);
  if (!u) return;
  AtFrame(c, *u, 0, "DMC-RT-002");
  const uint32_t end = std::min<uint32_t>(10, u->end);
  dmc::RtRunMove run = ShortRun(end);
  run.flags = dmc::kPlayPingPong;
  ExpectOk(c, "DMC-LOOP-001", h.Call(run));
  WaitRest(c, kRestWaitNs);
  const size_t mark = h.records().size();
  ExpectOk(c, "DMC-LOOP-001", Go(c));
  // An update of the run at frame k: MOVE TIME is "in thousandths of a
  // frame", and a device reporting on its own tick gives fractions (dmc-lite:
  // 10080, 10520); the nearest whole frame is the one it is at.
  const auto frame_report = [](const DmcRecord& r, auto pred) {
    const auto* p = As<dmc::MotorPositionReport>(&r);
    return r.request < 0 && p != nullptr && pred((p->move_time_x1000 + 500) / 1000);
  };
  const int at_end = h.WaitFor(mark, kLoopPassWaitNs, [&](const DmcRecord& r) {
    return frame_report(r, [&](uint32_t k) { return k == end; });
  });
  const int back =
      at_end < 0
          ? -1
          : h.WaitFor(static_cast<size_t>(at_end) + 1, kLoopPassWaitNs, [&](const DmcRecord& r) {
              return frame_report(r, [&](uint32_t k) { return k > 0 && k < end; });
            });
  if (!Expect(c, "DMC-LOOP-001", back >= 0, "a second, backward pass of the ping-pong run",
              at_end < 0 ? "frame " + std::to_string(end) + " never reported"
                         : "no frame reported on the way back")) {
    h.Call(dmc::MotorStopAll{});
    WaitRest(c, kRestWaitNs);
    return;
  }
  const size_t stop_mark = h.records().size();
  ExpectOk(c, "DMC-LOOP-001", h.Call(dmc::RtStopLoop{}));
  const int e = h.WaitFor(stop_mark, kStopLoopEndWaitNs,
                          [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
  if (!Expect(c, "DMC-LOOP-001", e >= 0, "RT_END once the run reaches frame 0",
              "no RT_END within 10 s of STOP_LOOP (the loop went on)")) {
    h.Call(dmc::MotorStopAll{});
    WaitRest(c, kRestWaitNs);
    return;
  }
  // The end point it stopped at: the last update before RT_END, at frame 0
  // by its MOVE TIME (to the nearest frame) or by where the rig is (every
  // motor within 2 steps of frame 0's upload: a device whose playback runs
  // offset from the upload, which DMC-RT-008 judges, still stops at the end
  // point).
  const dmc::MotorPositionReport* last = nullptr;
  for (size_t i = stop_mark; i < static_cast<size_t>(e); ++i) {
    const auto* p = As<dmc::MotorPositionReport>(&h.records()[i]);
    if (h.records()[i].request < 0 && p != nullptr) last = p;
  }
  WaitRest(c, kRestWaitNs);
  const auto rest = GetPositions(h);
  bool at_start = rest.has_value();
  for (size_t m = 0; at_start && m < u->path.size(); ++m) {
    at_start = std::abs(int64_t{At(*rest, m)} - u->path[m][0]) <= 2;
  }
  const bool frame0 = last != nullptr && (last->move_time_x1000 + 500) / 1000 == 0;
  std::string start_positions;
  for (size_t m = 0; m < u->path.size(); ++m) {
    start_positions += (m ? ", " : "") + std::to_string(u->path[m][0]);
  }
  Expect(c, "DMC-LOOP-001", frame0 || at_start,
         "the run ends at frame 0, its next end point (MOVE TIME near 0, or the rig at [" +
             start_positions + "])",
         (last ? "last MOVE TIME " + std::to_string(last->move_time_x1000) : "no update") +
             ", at rest at " + (rest ? Vec(*rest) : "no position"));
}

void VirtPosition(DmcCaseContext& c) {
  const DmcRecord* r = c.host.Call(dmc::VirtGetPositionRequest{});
  Expect(c, "DMC-VIRT-001", As<dmc::VirtPositionReport>(r) != nullptr, "VIRT_GET_POSITION response",
         Show(r));
}

// A boom-swing-track rig on motors 1..6 (boom 2.0 + level extension 0.5,
// angles 1000 steps per degree, track 10000 steps per unit), every POSITION 0.
constexpr int32_t kVirtAngleSpu = 1000;
constexpr int32_t kVirtTrackSpu = 10000;
constexpr int32_t kVirtTolerance = 200;  // 0.002 units or degrees, x100000

dmc::VirtRigBoomSwingTrack TestBoomRig() {
  dmc::VirtRigBoomSwingTrack b;
  b.boom = {1, kVirtAngleSpu, 0};
  b.swing = {2, kVirtAngleSpu, 0};
  b.track = {3, kVirtTrackSpu, 0};
  b.pan = {4, kVirtAngleSpu, 0};
  b.tilt = {5, kVirtAngleSpu, 0};
  b.roll = {6, kVirtAngleSpu, 0};
  b.boom_length_x1000 = 2000;
  b.boom_ext_x1000 = 500;
  return b;
}

bool ConfigureBoomRig(DmcCaseContext& c) {
  return ExpectOk(c, "DMC-VIRT-002", c.host.Call(dmc::VirtConfig{TestBoomRig()}));
}

void Unconfigure(DmcCaseContext& c) { c.host.Call(dmc::VirtConfig{dmc::VirtRigNone{}}); }

std::optional<dmc::VirtPositionReport> VirtPositions(DmcHost& h) {
  const auto* p = As<dmc::VirtPositionReport>(h.Call(dmc::VirtGetPositionRequest{}));
  if (p == nullptr) return std::nullopt;
  return *p;
}

void ExpectVirtAt(DmcCaseContext& c, std::string_view rule, const char* axis, int32_t got,
                  int32_t want) {
  c.v.Check(rule, std::abs(int64_t{got} - want) <= kVirtTolerance, [&] {
    return EvOf(c.host, nullptr, std::string(axis) + " " + std::to_string(want) + " (x100000)",
                std::to_string(got));
  });
}

void VirtConfigForms(DmcCaseContext& c) {
  DmcHost& h = c.host;
  constexpr uint32_t kModes = dmc::kCapVirtBoomSwingTrack | dmc::kCapVirtSwingPan |
                              dmc::kCapVirtYSwingTrack | dmc::kCapVirtXyz;
  const std::string caps = base::Hex(c.device.capabilities, 4);
  Expect(c, "DMC-VIRT-011", (c.device.capabilities & kModes) == kModes,
         "capabilities with 0x003c all set", caps);
  if ((c.device.capabilities & dmc::kCapVirtBoomSwingTrack) != 0 && c.device.motor_count >= 6) {
    // ERRATA 1.7: the table and SAFE DISTANCE are each optional.
    dmc::VirtRigBoomSwingTrack b = TestBoomRig();
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 93 bytes
    b.safe_distance_x1000 = 500;
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 97
    // A table in which the boom's present position is geometric 0 degrees,
    // one degree of axis per degree of angle.
    const auto p = GetPositions(h);
    const double boom_deg =
        static_cast<double>(At(p.value_or(std::vector<int32_t>{}), 0)) / kVirtAngleSpu;
    b.compensation.emplace();
    for (size_t i = 0; i < b.compensation->size(); ++i) {
      (*b.compensation)[i] = static_cast<int32_t>(
          std::lround((boom_deg + static_cast<double>(i) - 60.0) * dmc::kVirtPositionScale));
    }
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 581
    b.safe_distance_x1000.reset();
    ExpectOk(c, "DMC-VIRT-002", h.Call(dmc::VirtConfig{b}));  // 577
  }
  if ((c.device.capabilities & dmc::kCapVirtXyz) != 0 && c.device.motor_count >= 6) {
    // TYPE 8 with TYPE 1's layout: x-y-z in the bit-flag numbering.
    wire::Bytes data;
    dmc::EncodeData(dmc::HostMessage{dmc::VirtConfig{TestBoomRig()}}, data);
    dmc::VirtRigRaw raw;
    raw.type = static_cast<uint8_t>(dmc::RigType::kXyzFlag);
    raw.data.assign(data.begin() + 1, data.end());
    const DmcRecord* r = h.Call(dmc::VirtConfig{raw});
    const std::optional<uint32_t> code = AckCodeOf(r);
    c.v.Check("DMC-VIRT-012", code && *code != ToWire(AckCode::kOk), [&] {
      return EvOf(h, r, "TYPE 8 refused (the spec numbers the rigs 0..4)",
                  CodeText(r) + ": TYPE 8 taken as x-y-z (bit-flag numbering)");
    });
  }
  Unconfigure(c);
}

void VirtMoveReadBack(DmcCaseContext& c) {
  DmcHost& h = c.host;
  if (!ConfigureBoomRig(c)) return;
  const auto p0 = VirtPositions(h);
  if (!p0) return;
  // 0.1 units along the track, then 0.1 units up.
  ExpectOk(c, "DMC-VIRT-003", h.Call(dmc::VirtMove{1, p0->track_x100000 + 10000}));
  WaitRest(c, kRestWaitNs);
  const auto p1 = VirtPositions(h);
  if (!p1) return;
  ExpectVirtAt(c, "DMC-VIRT-003", "vTrack", p1->track_x100000, p0->track_x100000 + 10000);
  ExpectOk(c, "DMC-VIRT-003", h.Call(dmc::VirtMove{3, p1->ns_x100000 + 10000}));
  WaitRest(c, kRestWaitNs);
  const auto p2 = VirtPositions(h);
  if (!p2) return;
  ExpectVirtAt(c, "DMC-VIRT-003", "vNS", p2->ns_x100000, p1->ns_x100000 + 10000);
  ExpectVirtAt(c, "DMC-VIRT-003", "vTrack", p2->track_x100000, p1->track_x100000);
  // 6 units above a boom of 2: out of reach.
  const auto steps = GetPositions(h);
  const DmcRecord* r = h.Call(dmc::VirtMove{3, p2->ns_x100000 + 600000});
  ExpectRefused(c, "DMC-VIRT-004", r);
  ExpectCode(c, "DMC-VIRT-005", r, AckCode::kErrRange);
  h.Idle(kRefusedVirtMoveShowNs);
  const auto after = GetPositions(h);
  Expect(c, "DMC-VIRT-004", steps && after && *steps == *after,
         "motor positions unchanged: " + (steps ? Vec(*steps) : std::string("?")),
         after ? Vec(*after) : std::string("no MOTOR_GET_POSITION answer"));
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtMove{0, 0}), AckCode::kErrRange);
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtMove{7, 0}), AckCode::kErrRange);
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtStop{0}), AckCode::kErrRange);
  ExpectCode(c, "DMC-VIRT-006", h.Call(dmc::VirtStop{7}), AckCode::kErrRange);
  Unconfigure(c);
}

void VirtStopShort(DmcCaseContext& c) {
  DmcHost& h = c.host;
  if (!ConfigureBoomRig(c)) return;
  const auto p0 = VirtPositions(h);
  if (!p0) return;
  // 20 units: far enough to stop short of.
  const int32_t far = p0->track_x100000 + 20 * dmc::kVirtPositionScale;
  ExpectOk(c, "DMC-VIRT-007", h.Call(dmc::VirtMove{1, far}));
  h.Idle(kVirtRunBeforeStopNs);
  ExpectOk(c, "DMC-VIRT-007", h.Call(dmc::VirtStop{1}));
  Expect(c, "DMC-VIRT-007", WaitRest(c, kStopRestWaitNs),
         "the rig at rest within 10 s of VIRT_STOP", "still moving");
  const auto p1 = VirtPositions(h);
  if (!p1) return;
  Expect(c, "DMC-VIRT-007", p1->track_x100000 < far - kVirtTolerance,
         "vTrack short of " + std::to_string(far), std::to_string(p1->track_x100000));
  h.Call(dmc::VirtMove{1, p0->track_x100000});
  WaitRest(c, kRestWaitNs);
  Unconfigure(c);
}

void VirtJogs(DmcCaseContext& c) {
  DmcHost& h = c.host;
  if (!ConfigureBoomRig(c)) return;
  const auto p0 = VirtPositions(h);
  if (!p0) return;
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJog{1, dmc::kJogSpeedMax, p0->track_x100000 + 5000}));
  WaitRest(c, kRestWaitNs);
  if (const auto p1 = VirtPositions(h)) {
    ExpectVirtAt(c, "DMC-VIRT-008", "vTrack", p1->track_x100000, p0->track_x100000 + 5000);
  }
  // Along the camera line, then speed 0; the pan, then VIRT_STOP.
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJogOnLine{2, 5000}));
  h.Idle(kVirtJogBeforeStopNs);
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJogOnLine{2, 0}));
  Expect(c, "DMC-VIRT-008", WaitRest(c, kStopRestWaitNs), "at rest within 10 s of speed 0",
         "still moving");
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtJogOnLine{3, -3000}));
  h.Idle(kVirtJogBeforeStopNs);
  ExpectOk(c, "DMC-VIRT-008", h.Call(dmc::VirtStop{4}));
  Expect(c, "DMC-VIRT-008", WaitRest(c, kStopRestWaitNs), "at rest within 10 s of VIRT_STOP",
         "still moving");
  Unconfigure(c);
}

void VirtAim(DmcCaseContext& c) {
  DmcHost& h = c.host;
  for (const dmc::VirtAimPoint& a :
       {dmc::VirtAimPoint{1, 1500, -250, 9000}, dmc::VirtAimPoint{0, 1500, -250, 9000}}) {
    const DmcRecord* r = h.Call(a);
    const auto* echo = As<dmc::VirtAimPoint>(r);
    c.v.Check("DMC-VIRT-009", echo != nullptr && *echo == a, [&] {
      return EvOf(h, r, "VIRT_AIM_POINT enable=" + std::to_string(a.enable) + " 1500,-250,9000",
                  Show(r));
    });
    const auto p = VirtPositions(h);
    const bool same = p && p->aim && p->aim->enabled == a.enable && p->aim->x_x1000 == a.x_x1000 &&
                      p->aim->y_x1000 == a.y_x1000 && p->aim->z_x1000 == a.z_x1000;
    Expect(c, "DMC-VIRT-010", same,
           "aim fields enabled=" + std::to_string(a.enable) + " 1500,-250,9000",
           p && p->aim ? "enabled=" + std::to_string(p->aim->enabled) + " " +
                             std::to_string(p->aim->x_x1000) + "," +
                             std::to_string(p->aim->y_x1000) + "," + std::to_string(p->aim->z_x1000)
                       : std::string("no aim fields"));
  }
}

}  // namespace moco::conformance::dmc_cases
