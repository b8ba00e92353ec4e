// DMC v2 real-time output cases (dmc-v2-protocol.txt "MSG_RT_UPLOAD_MOVE_DMX",
// "MSG_RT_UPLOAD_MOVE_TRIGGERS", "MSG_RT_POSITION_FRAME", "MSG_RT_RUN_MOVE"
// SYNC DMX, BLOOP, FLAGS and camera angles, "MSG_FLAG_ACK" ERR_PREROLL /
// ERR_POSTROLL; ERRATA 1.7; FACTS "DMC v2" playback flags): what a run plays
// besides the motors. The ACKs are judged on any target; the DMX levels,
// GIO outputs and camera lines only where the runner can read them
// (Target::Outputs(), in-process), and are otherwise not exercised. Listed by
// the table in dmc_cases.cpp.
#include <algorithm>
#include <cstdlib>
#include <initializer_list>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "base/format.h"
#include "conformance/protocols/dmc/dmc_cases_internal.h"

namespace moco::conformance::dmc_cases {

using dmc::AckCode;
using dmc::MsgType;
using dmc::ToWire;

namespace {

// The uploaded DMX levels of the cases: channel 1 rises 10 a frame from 5
// over frames 0..10 (two sections, the second the last set), channel 2 falls
// 15 a frame from 200 over frames 0..7 (last set); both then hold.
struct DmxTrack {
  uint16_t channel;
  std::vector<uint8_t> levels;  // frames 0..last
};

std::vector<DmxTrack> DmxTracks(const dmc::HiResponse& hi, uint32_t end) {
  std::vector<DmxTrack> out;
  const int last1 = static_cast<int>(std::min<uint32_t>(10, end));
  DmxTrack a{1, {}};
  for (int k = 0; k <= last1; ++k) a.levels.push_back(static_cast<uint8_t>(5 + 10 * k));
  out.push_back(a);
  if (hi.dmx_count >= 2) {
    const int last2 = static_cast<int>(std::min<uint32_t>(7, end));
    DmxTrack b{2, {}};
    for (int k = 0; k <= last2; ++k) b.levels.push_back(static_cast<uint8_t>(200 - 15 * k));
    out.push_back(b);
  }
  return out;
}

// The level a track gives frame k (the last set repeats).
uint8_t LevelAt(const DmxTrack& t, uint32_t k) {
  return t.levels[std::min<size_t>(k, t.levels.size() - 1)];
}

// Sends the tracks: channel 1 in two sections (frames 0..4, then the rest as
// the last set), the others in one; every ACK is judged by DMC-DMX-005.
void SendDmx(DmcCaseContext& c, const std::vector<DmxTrack>& tracks) {
  for (const DmxTrack& t : tracks) {
    const size_t split = t.channel == 1 ? std::min<size_t>(5, t.levels.size() - 1) : 0;
    if (split > 0) {
      const std::vector<uint8_t> first(t.levels.begin(),
                                       t.levels.begin() + static_cast<std::ptrdiff_t>(split));
      ExpectOk(c, "DMC-DMX-005", c.host.Call(dmc::RtUploadMoveDmx{t.channel, 0, false, first}));
    }
    const std::vector<uint8_t> rest(t.levels.begin() + static_cast<std::ptrdiff_t>(split),
                                    t.levels.end());
    ExpectOk(
        c, "DMC-DMX-005",
        c.host.Call(dmc::RtUploadMoveDmx{t.channel, static_cast<uint32_t>(split), true, rest}));
  }
}

std::string Levels(const std::vector<int>& v) {
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return s + "]";
}

// Channel levels of the device now (-1 where it cannot be read).
std::vector<int> ReadDmx(const Target& t, const std::vector<DmxTrack>& tracks) {
  std::vector<int> out;
  const DmxOutput* dmx = t.Outputs().dmx;
  for (const DmxTrack& k : tracks) out.push_back(dmx != nullptr ? dmx->Value(k.channel) : -1);
  return out;
}

// Judges the DMX levels now against frame `frame` of the tracks.
void ExpectDmxAt(DmcCaseContext& c, std::string_view rule, const std::vector<DmxTrack>& tracks,
                 uint32_t frame, const std::string& when) {
  std::vector<int> want;
  for (const DmxTrack& t : tracks) want.push_back(LevelAt(t, frame));
  const std::vector<int> got = ReadDmx(c.target, tracks);
  Expect(
      c, rule, got == want,
      "DMX channels 1.. at frame " + std::to_string(frame) + " levels " + Levels(want) + " " + when,
      Levels(got));
}

// What the runner saw of a run it started with GO.
struct Watched {
  const DmcRecord* go = nullptr;  // GO's ACK OK; null when GO was refused
  TimeNs go_ns = 0;
  int end = -1;  // the RT_END record, -1 when none came
  // Per frame index (frame - start): the first report carrying that frame's
  // MOVE TIME, and the outputs sampled last while it was the frame reported.
  std::map<uint32_t, TimeNs> first_report_ns;
  std::map<uint32_t, std::vector<int>> dmx;
  std::map<uint32_t, uint32_t> gio;
  // Every sample of the GIO outputs and of one DMX channel (and of every
  // track's channel), in time order.
  struct Sample {
    TimeNs t_ns;
    uint32_t gio;
    int dmx;
    std::vector<int> levels;
  };
  std::vector<Sample> samples;
  // When the frame clock stood on START FRAME, read from the reports whose
  // MOVE TIME lies strictly inside the run (a device on a velocity tick
  // reports the clock at its tick, fractional: 10080 is 8% into frame 10;
  // FACTS "DMC v2"), the median of their readings; unset without any.
  std::optional<TimeNs> clock_origin_ns;
};

// The frame clock's origin from the reports (Watched::clock_origin_ns) and,
// for every frame, the outputs sampled last inside the frame's interval by
// that clock (a device reporting each whole frame gives the same frames as
// its reports; one on a tick names only some).
void ReadFrameClock(Watched& w, const std::vector<std::pair<TimeNs, uint32_t>>& clock,
                    uint32_t start, uint32_t end) {
  std::vector<TimeNs> origins;
  for (const auto& [t, m] : clock) {
    const double frames = static_cast<double>(m) / 1000.0 - static_cast<double>(start);
    origins.push_back(t - static_cast<TimeNs>(frames * static_cast<double>(kRunFrameNs)));
  }
  if (origins.empty()) return;
  std::nth_element(origins.begin(),
                   origins.begin() + static_cast<std::ptrdiff_t>(origins.size() / 2),
                   origins.end());
  w.clock_origin_ns = origins[origins.size() / 2];
  for (uint32_t k = 0; k <= end - start; ++k) {
    const TimeNs from = *w.clock_origin_ns + static_cast<TimeNs>(k) * kRunFrameNs;
    const Watched::Sample* last = nullptr;
    for (const Watched::Sample& s : w.samples) {
      if (s.t_ns >= from && s.t_ns < from + kRunFrameNs) last = &s;
    }
    if (last == nullptr) continue;
    w.gio[k] = last->gio;
    w.dmx[k] = last->levels;
  }
}

// GO (DMC-RT-015's retries included), then reads until RT_END or kRunEndWaitNs.
// Where the outputs are observable it samples them every kOutputSampleNs (2 ms),
// and each time a frame report (MOVE TIME frame x 1000, frames start..end) has
// come in.
Watched GoAndWatch(DmcCaseContext& c, std::string_view go_rule, uint32_t start, uint32_t end,
                   const std::vector<DmxTrack>& tracks, int sampled_channel) {
  DmcHost& h = c.host;
  Watched w;
  const size_t mark = h.records().size();
  w.go_ns = h.Now();
  const DmcRecord* go = Go(c);
  if (!ExpectOk(c, go_rule, go)) return w;  // nothing runs: w.go stays null
  w.go = go;
  const DeviceOutputs out = c.target.Outputs();
  const bool observe = out.gio != nullptr || out.dmx != nullptr;
  size_t next = mark;
  std::optional<uint32_t> reported;                // the frame index the last frame report named
  std::vector<std::pair<TimeNs, uint32_t>> clock;  // (time, MOVE TIME) inside the run
  const TimeNs until = h.Now() + kRunEndWaitNs;
  while (w.end < 0 && h.Now() < until && !h.link_lost()) {
    if (observe) {
      h.Idle(kOutputSampleNs);
    } else {
      h.WaitFor(next, until - h.Now(),
                [](const DmcRecord& r) { return IsUnsolicited(r, MsgType::kRtEnd); });
    }
    for (; next < h.records().size(); ++next) {
      const DmcRecord& r = h.records()[next];
      if (IsUnsolicited(r, MsgType::kRtEnd) && w.end < 0) w.end = static_cast<int>(next);
      const auto* p = As<dmc::MotorPositionReport>(&r);
      if (r.request >= 0 || p == nullptr) continue;
      if (p->move_time_x1000 > start * 1000 && p->move_time_x1000 < end * 1000) {
        clock.emplace_back(r.t_ns, p->move_time_x1000);
      }
      if (p->move_time_x1000 % 1000 != 0) continue;
      const uint32_t f = p->move_time_x1000 / 1000;
      if (f < start || f > end) continue;
      w.first_report_ns.emplace(f - start, r.t_ns);
      reported = f - start;
    }
    if (!observe) continue;
    const uint32_t g = out.gio != nullptr ? out.gio->outputs() : 0;
    const int d = out.dmx != nullptr && sampled_channel > 0 ? out.dmx->Value(sampled_channel) : -1;
    w.samples.push_back({h.Now(), g, d, ReadDmx(c.target, tracks)});
    if (reported) {
      w.dmx[*reported] = w.samples.back().levels;
      w.gio[*reported] = g;
    }
  }
  ReadFrameClock(w, clock, start, end);
  return w;
}

// The spans [on, off) in which `on(sample)` held, from the samples.
std::vector<std::pair<TimeNs, TimeNs>> Spans(
    const Watched& w, const std::function<bool(const Watched::Sample&)>& on) {
  std::vector<std::pair<TimeNs, TimeNs>> out;
  bool in = false;
  for (const Watched::Sample& s : w.samples) {
    if (on(s) && !in) out.push_back({s.t_ns, s.t_ns});
    if (on(s)) out.back().second = s.t_ns;
    in = on(s);
  }
  return out;
}

std::string SpansText(const std::vector<std::pair<TimeNs, TimeNs>>& spans) {
  std::string s;
  for (const auto& [a, b] : spans) {
    s += (s.empty() ? "" : ", ") + std::to_string(a / kMs) + ".." + std::to_string(b / kMs) + " ms";
  }
  return s.empty() ? "never" : s;
}

// A bloop of about `ms`: one span, lasting half to one and a half times it
// (kBloopSlackNs either way: the samples are kOutputSampleNs apart).
bool BloopLike(const std::vector<std::pair<TimeNs, TimeNs>>& spans, uint16_t ms) {
  if (spans.size() != 1) return false;
  const TimeNs d = spans[0].second - spans[0].first;
  const TimeNs bloop = TimeNs{ms} * kMs;
  return d >= bloop / 2 - kBloopSlackNs && d <= bloop * 3 / 2 + kBloopSlackNs;
}

// The target cannot read the device's outputs: `rules`, judged on them, are
// not exercised, and say why.
void LogNotObserved(DmcCaseContext& c, const char* what,
                    std::initializer_list<std::string_view> rules) {
  const std::string why = std::string("the target's outputs cannot be read: ") + what +
                          " not exercised (in-process targets read them)";
  c.log.push_back(why);
  for (const std::string_view id : rules) c.v.NotExercised(id, why);
}

void EndRun(DmcCaseContext& c, const Watched& w) {
  Expect(c, "DMC-RT-005", w.go == nullptr || w.end >= 0, "RT_END after the run",
         "none within 20 s");
  if (w.end < 0) c.host.Call(dmc::MotorStopAll{});
  WaitRest(c, kRestWaitNs);
}

}  // namespace

// ---------------------------------------------------------------- DMX upload

// MSG_RT_UPLOAD_MOVE_DMX sections with the move ("only if the device also
// support DMX"), refusals of sections the device cannot hold, then
// MSG_RT_POSITION_FRAME "send all motors (and DMX if applicable) to the
// uploaded frame position", before and after the last set.
void UploadDmx(DmcCaseContext& c) {
  DmcHost& h = c.host;
  std::vector<DmxTrack> tracks;
  const auto u = Upload(c, [&](uint32_t end) {
    tracks = DmxTracks(c.device, end);
    SendDmx(c, tracks);
    // Channel 0, a channel past DMX COUNT, and frames past END FRAME.
    const auto bad_channel = static_cast<uint16_t>(c.device.dmx_count + 1);
    ExpectCode(c, "DMC-DMX-006", h.Call(dmc::RtUploadMoveDmx{0, 0, true, {9}}), AckCode::kErrRange);
    ExpectCode(c, "DMC-DMX-006", h.Call(dmc::RtUploadMoveDmx{bad_channel, 0, true, {9}}),
               AckCode::kErrRange);
    ExpectCode(c, "DMC-DMX-006", h.Call(dmc::RtUploadMoveDmx{1, end + 1, true, {9, 9}}),
               AckCode::kErrRange);
  });
  if (!u || tracks.empty()) return;
  const bool observe = c.target.Outputs().dmx != nullptr;
  if (!observe) LogNotObserved(c, "DMX levels at uploaded frames", {"DMC-DMX-007", "DMC-DMX-008"});
  const uint32_t mid = std::min<uint32_t>(3, u->end);
  AtFrame(c, *u, mid, "DMC-RT-002");
  if (observe) ExpectDmxAt(c, "DMC-DMX-007", tracks, mid, "after RT_POSITION_FRAME");
  // Past both channels' last sets: the final levels repeat.
  AtFrame(c, *u, u->end, "DMC-RT-002");
  if (observe) ExpectDmxAt(c, "DMC-DMX-008", tracks, u->end, "(last sets repeated)");
  AtFrame(c, *u, 0, "DMC-RT-002");
  if (observe) ExpectDmxAt(c, "DMC-DMX-007", tracks, 0, "after RT_POSITION_FRAME");
}

// ---------------------------------------------------------------- SYNC DMX

// MSG_RT_RUN_MOVE "SYNC DMX BYTE 1=Play back upload DMX, 0=don't play DMX":
// a run with 1 plays each frame's uploaded levels; a run with 0 leaves the
// lights as MSG_DMX set them. The second run also bloops on a DMX channel
// ("BLOOP DMX CHANNEL WORD 0=None, 1-512 = a channel for the BLOOP").
void SyncRun(DmcCaseContext& c) {
  DmcHost& h = c.host;
  std::vector<DmxTrack> tracks;
  const auto u = Upload(c, [&](uint32_t end) {
    tracks = DmxTracks(c.device, end);
    SendDmx(c, tracks);
  });
  if (!u || tracks.empty()) return;
  const bool observe = c.target.Outputs().dmx != nullptr;
  if (!observe) LogNotObserved(c, "DMX playback", {"DMC-DMX-009", "DMC-DMX-010", "DMC-DMX-011"});
  const uint32_t end = std::min<uint32_t>(10, u->end);
  AtFrame(c, *u, 0, "DMC-RT-002");
  dmc::RtRunMove run = ShortRun(end);
  run.sync_dmx = 1;
  ExpectOk(c, "DMC-RT-009", h.Call(run));
  WaitRest(c, kRestWaitNs);
  Watched w = GoAndWatch(c, "DMC-RT-009", 0, end, tracks, 0);
  if (observe && w.go != nullptr) {
    for (uint32_t k = 0; k <= end; ++k) {
      auto it = w.dmx.find(k);
      std::vector<int> want;
      for (const DmxTrack& t : tracks) want.push_back(LevelAt(t, k));
      Expect(
          c, "DMC-DMX-009", it != w.dmx.end() && it->second == want,
          "DMX levels " + Levels(want) + " at frame " + std::to_string(k) + " of a SYNC DMX 1 run",
          it == w.dmx.end() ? "frame " + std::to_string(k) + " never reported"
                            : Levels(it->second));
    }
  }
  EndRun(c, w);

  // SYNC DMX 0: the lights stay as MSG_DMX left them; the bloop channel (3,
  // when the device has it) goes up for about BLOOP TIME and back.
  std::vector<uint8_t> fixed(tracks.size(), 77);
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, fixed}));
  const uint16_t bloop_channel = c.device.dmx_count >= 3 ? 3 : 0;
  if (bloop_channel != 0) ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, bloop_channel, {0}}));
  AtFrame(c, *u, 0, "DMC-RT-002");
  // POSITION_FRAME brought the uploaded levels back: set the lights again.
  ExpectOk(c, "DMC-DMX-001", h.Call(dmc::Dmx{0, 1, fixed}));
  run.sync_dmx = 0;
  run.bloop_dmx_channel = bloop_channel;
  run.bloop_time_ms = kBloopMs;
  ExpectOk(c, "DMC-RT-009", h.Call(run));
  WaitRest(c, kRestWaitNs);
  w = GoAndWatch(c, "DMC-RT-009", 0, end, tracks, bloop_channel);
  if (observe && w.go != nullptr) {
    const std::vector<int> want(tracks.size(), 77);
    bool same = !w.dmx.empty();
    std::string seen;
    for (const auto& [k, levels] : w.dmx) {
      if (levels != want && same) seen = "frame " + std::to_string(k) + ": " + Levels(levels);
      same = same && levels == want;
    }
    Expect(c, "DMC-DMX-010", same, "DMX levels " + Levels(want) + " all through a SYNC DMX 0 run",
           w.dmx.empty() ? "no frame reported" : seen);
    if (bloop_channel != 0) {
      const auto spans = Spans(w, [](const Watched::Sample& s) { return s.dmx == 255; });
      const auto moved = Spans(w, [](const Watched::Sample& s) { return s.dmx > 0; });
      Expect(c, "DMC-DMX-011", BloopLike(spans, kBloopMs) && moved.size() == 1,
             "DMX channel 3 at 255 once, for about 200 ms (BLOOP TIME), then back to 0",
             "at 255: " + SpansText(spans) + "; above 0: " + SpansText(moved));
    }
  }
  EndRun(c, w);
}

// ---------------------------------------------------------------- triggers

// MSG_RT_UPLOAD_MOVE_TRIGGERS ("Only sends frame/value pairs where one or more
// triggers is on"), a frame index past the upload, then a SYNC DMX run: the
// masked GIO outputs follow the uploaded values frame by frame, and an output
// outside the mask bloops ("BLOOP LOCATION DWORD GIO Outputs for 'bloop'
// signal").
void Triggers(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const int outs = c.device.gio_out_count;
  const uint32_t mask = outs >= 3 ? 0x3u : 0x1u;
  const uint32_t bloop = outs >= 2 ? 1u << (outs - 1) : 0u;
  std::map<uint32_t, uint32_t> values;  // frame index -> trigger values
  const auto u = Upload(c, [&](uint32_t end) {
    std::vector<dmc::TriggerPoint> points;
    for (const auto& [k, v] :
         std::map<uint32_t, uint32_t>{{2, 0x1}, {3, mask}, {6, mask & 0x2 ? 0x2u : 0x1u}}) {
      if (k > end) continue;
      values[k] = v;
      points.push_back({k, v});
    }
    ExpectOk(c, "DMC-RT-017", h.Call(dmc::RtUploadMoveTriggers{mask, points}));
    ExpectCode(c, "DMC-RT-018", h.Call(dmc::RtUploadMoveTriggers{mask, {{end + 1, 0x1}}}),
               AckCode::kErrRange);
  });
  if (!u) return;
  const bool observe = c.target.Outputs().gio != nullptr;
  if (!observe) LogNotObserved(c, "trigger and bloop outputs", {"DMC-RT-019", "DMC-RT-020"});
  ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{0}));
  const uint32_t end = std::min<uint32_t>(10, u->end);
  AtFrame(c, *u, 0, "DMC-RT-002");
  dmc::RtRunMove run = ShortRun(end);
  run.sync_dmx = 1;
  run.bloop_outputs = bloop;
  run.bloop_time_ms = kBloopMs;
  ExpectOk(c, "DMC-RT-009", h.Call(run));
  WaitRest(c, kRestWaitNs);
  const Watched w = GoAndWatch(c, "DMC-RT-009", 0, end, {}, 0);
  if (observe && w.go != nullptr) {
    for (uint32_t k = 0; k <= end; ++k) {
      auto it = w.gio.find(k);
      const uint32_t want = values.count(k) ? values[k] : 0;
      Expect(c, "DMC-RT-019", it != w.gio.end() && (it->second & mask) == want,
             "GIO outputs " + base::Hex(want, 2) + " under mask " + base::Hex(mask, 2) +
                 " at frame " + std::to_string(k),
             it == w.gio.end() ? "frame " + std::to_string(k) + " never reported"
                               : base::Hex(it->second & mask, 2));
    }
    if (bloop != 0) {
      const auto spans =
          Spans(w, [bloop](const Watched::Sample& s) { return (s.gio & bloop) != 0; });
      Expect(c, "DMC-RT-020", BloopLike(spans, kBloopMs),
             "GIO output " + std::to_string(outs) + " on once, for about 200 ms (BLOOP TIME)",
             "on: " + SpansText(spans));
    }
  }
  EndRun(c, w);
  ExpectOk(c, "DMC-GIO-003", h.Call(dmc::GioOut{0}));
}

// ---------------------------------------------------------------- camera

namespace {

// The shutter presses (closing edge to opening edge) from `from_ns` on.
std::vector<std::pair<TimeNs, TimeNs>> Presses(const CameraOutput& cam, TimeNs from_ns) {
  std::vector<std::pair<TimeNs, TimeNs>> out;
  for (const sim::CameraPort::Edge& e : cam.Trace()) {
    if (e.line != sim::CameraPort::kShutter || e.time_ns < from_ns) continue;
    if (e.level) {
      out.push_back({e.time_ns, -1});
    } else if (!out.empty() && out.back().second < 0) {
      out.back().second = e.time_ns;
    }
  }
  return out;
}

// Frame index k's time: its first frame report, or one frame interval from
// the next one's (frame 0's MOVE TIME may also be carried by pre-roll
// reports), or where the frame clock the reports read puts it.
std::optional<TimeNs> FrameTime(const Watched& w, uint32_t k) {
  if (k > 0) {
    auto it = w.first_report_ns.find(k);
    if (it != w.first_report_ns.end()) return it->second;
  }
  auto next = w.first_report_ns.find(k + 1);
  if (next != w.first_report_ns.end()) return next->second - kRunFrameNs;
  if (w.clock_origin_ns) return *w.clock_origin_ns + static_cast<TimeNs>(k) * kRunFrameNs;
  return std::nullopt;
}

dmc::RtRunMove CameraRun(uint32_t end, uint16_t flags, uint16_t open, uint16_t close) {
  dmc::RtRunMove run = ShortRun(end);
  run.flags = flags;
  run.camera_open_angle_deg = open;
  run.camera_close_angle_deg = close;
  return run;
}

}  // namespace

// FLAGS "0x20 is camera trigger for every frame (stills)" with CAMERA OPEN
// ANGLE 90 and CLOSE ANGLE 270: one exposure per frame, open for the middle
// half of the frame's interval. An angle past 360 first.
void CameraStills(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  const uint32_t end = std::min<uint32_t>(10, u->end);
  AtFrame(c, *u, 0, "DMC-RT-002");
  bool armed = false;
  for (const auto& [open, close] : {std::pair<uint16_t, uint16_t>{0, 400}, {361, 360}}) {
    const DmcRecord* r = h.Call(CameraRun(end, dmc::kPlayCameraStills, open, close));
    ExpectCode(c, "DMC-RT-024", r, AckCode::kErrRange);
    armed = armed || AckCodeOf(r) == static_cast<uint32_t>(AckCode::kOk);
  }
  if (armed) {
    // A device that took a run with angles past 360 armed it, and may have
    // left for its pre-roll: disarm it (STOP_ALL with a flag: no hard-stop
    // state) and stand on frame 0 again, so DMC-RT-021 judges the good run
    // from where it would come, not from the other rule's fault.
    dmc::MotorStopAll stop;
    stop.flags = dmc::kStopAllSilent;
    h.Call(stop);
    WaitRest(c, kRestWaitNs);
    AtFrame(c, *u, 0, "DMC-RT-002");
  }
  ExpectOk(c, "DMC-RT-021", h.Call(CameraRun(end, dmc::kPlayCameraStills, 90, 270)));
  WaitRest(c, kRestWaitNs);
  const CameraOutput* cam = c.target.Outputs().camera;
  if (cam == nullptr) LogNotObserved(c, "camera exposures", {"DMC-RT-022", "DMC-RT-023"});
  const Watched w = GoAndWatch(c, "DMC-RT-021", 0, end, {}, 0);
  Expect(c, "DMC-RT-021", w.go == nullptr || w.end >= 0, "RT_END after the stills run",
         "none within 20 s");
  if (cam != nullptr && w.go != nullptr) {
    h.Idle(kLastExposureCloseNs);
    const auto presses = Presses(*cam, w.go_ns);
    Expect(c, "DMC-RT-022", presses.size() == end + 1,
           std::to_string(end + 1) + " exposures (one per frame 0.." + std::to_string(end) + ")",
           std::to_string(presses.size()) + " shutter presses: " + SpansText(presses));
    const TimeNs tol = kExposureEdgeTolNs;
    for (uint32_t k = 0; k <= end && presses.size() == end + 1; ++k) {
      const std::optional<TimeNs> t = FrameTime(w, k);
      const TimeNs open = t ? *t + kRunFrameNs / 4 : 0, close = t ? *t + kRunFrameNs * 3 / 4 : 0;
      const auto& p = presses[k];
      Expect(c, "DMC-RT-023",
             t && std::llabs(p.first - open) <= tol && p.second >= 0 &&
                 std::llabs(p.second - close) <= tol,
             "frame " + std::to_string(k) + "'s shutter open from about " +
                 std::to_string(open / kMs) + " to " + std::to_string(close / kMs) +
                 " ms (90 to 270 degrees)",
             t ? std::to_string(p.first / kMs) + " to " + std::to_string(p.second / kMs) + " ms"
               : "frame " + std::to_string(k) + " never reported");
    }
  }
  EndRun(c, w);
}

// FLAGS "0x10 is camera trigger at start/stop of move (video)": one press of
// the shutter line as the run reaches its start frame, one at its end frame.
void CameraVideo(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  const uint32_t end = std::min<uint32_t>(10, u->end);
  AtFrame(c, *u, 0, "DMC-RT-002");
  dmc::RtRunMove run = ShortRun(end);
  run.flags = dmc::kPlayCameraVideo;  // no angles: "Only used if camera trigger for every frame"
  ExpectOk(c, "DMC-RT-021", h.Call(run));
  WaitRest(c, kRestWaitNs);
  const CameraOutput* cam = c.target.Outputs().camera;
  if (cam == nullptr) LogNotObserved(c, "camera video triggers", {"DMC-RT-025"});
  const Watched w = GoAndWatch(c, "DMC-RT-021", 0, end, {}, 0);
  Expect(c, "DMC-RT-021", w.go == nullptr || w.end >= 0, "RT_END after the video run",
         "none within 20 s");
  if (cam != nullptr && w.go != nullptr) {
    h.Idle(kVideoPressesSettleNs);
    const auto presses = Presses(*cam, w.go_ns);
    const std::optional<TimeNs> t0 = FrameTime(w, 0), tn = FrameTime(w, end);
    const TimeNs late = kVideoPressLateNs;
    const bool ok = t0 && tn && presses.size() == 2 && presses[0].first >= *t0 - kRunFrameNs &&
                    presses[0].first <= *t0 + late && presses[1].first >= *tn - kRunFrameNs &&
                    presses[1].first <= *tn + late;
    Expect(c, "DMC-RT-025", ok,
           "two shutter presses: at the start frame (" +
               (t0 ? std::to_string(*t0 / kMs) : std::string("?")) + " ms) and the end frame (" +
               (tn ? std::to_string(*tn / kMs) : std::string("?")) + " ms)",
           std::to_string(presses.size()) + " presses: " + SpansText(presses));
  }
  EndRun(c, w);
}

// ---------------------------------------------------------------- pre-/post-roll

// Soft limits on motor 1 around the uploaded path (100 steps of margin each
// side): a 500 ms pre-roll (240 steps before frame 0 at 960 steps/s) passes
// the lower one, a 500 ms post-roll (240 steps past frame 10) the upper one;
// 100 ms of each (48 steps) stays within. ERR_PREROLL "A real-time move
// preroll failed, usually because preroll would send motors past limits";
// ERR_POSTROLL "... usually because a limit check failed".
void RollLimits(DmcCaseContext& c) {
  DmcHost& h = c.host;
  const auto u = Upload(c);
  if (!u) return;
  const uint32_t end = std::min<uint32_t>(10, u->end);
  if (end < 10) {
    const std::string why =
        "the device holds fewer than 11 frames: pre-/post-roll limits not exercised";
    c.log.push_back(why);
    for (const char* id : {"DMC-RT-026", "DMC-RT-027", "DMC-RT-028", "DMC-RT-029"}) {
      c.v.NotExercised(id, why);
    }
    return;
  }
  AtFrame(c, *u, 0, "DMC-RT-002");
  const int32_t p0 = u->path[0][0];
  const int32_t lo = p0 - 100, hi = u->path[0][end] + 100;
  ExpectOk(c, "DMC-CFG-005",
           h.Call(dmc::MotorSetLimits{1, dmc::kLimitEnabled, lo, dmc::kLimitEnabled, hi, 0}));
  dmc::RtRunMove run = ShortRun(end);
  // A run the rolls take past a limit: refused with `want`, nothing moved.
  auto past_limit = [&](uint32_t pre_ms, uint32_t post_ms, std::string_view rule, AckCode want) {
    run.preroll_ms = pre_ms;
    run.postroll_ms = post_ms;
    const auto before = GetPositions(h);
    const DmcRecord* r = h.Call(run);
    ExpectCode(c, rule, r, want);
    h.Idle(kRefusedRunShowNs);
    WaitRest(c, kRestWaitNs);
    const auto after = GetPositions(h);
    const std::optional<uint32_t> code = AckCodeOf(r);
    if (code && *code == ToWire(AckCode::kOk)) {
      // Accepted after all: disarmed before going on.
      h.Call(dmc::MotorStopAll{});
      WaitRest(c, kRestWaitNs);
      AtFrame(c, *u, 0, "DMC-RT-002");
      return;
    }
    Expect(c, "DMC-RT-028", before && after && *before == *after,
           "motor positions unchanged after the refusal: " +
               (before ? Vec(*before) : std::string("?")),
           after ? Vec(*after) : std::string("no MOTOR_GET_POSITION answer"));
    if (before && after && *before != *after) AtFrame(c, *u, 0, "DMC-RT-002");
  };
  past_limit(kRollPastLimitMs, 0, "DMC-RT-026", AckCode::kErrPreroll);
  past_limit(0, kRollPastLimitMs, "DMC-RT-027", AckCode::kErrPostroll);
  run.preroll_ms = kRollWithinLimitMs;
  run.postroll_ms = kRollWithinLimitMs;
  if (ExpectOk(c, "DMC-RT-029", h.Call(run))) {
    WaitRest(c, kRestWaitNs);
    const Watched w = GoAndWatch(c, "DMC-RT-029", 0, end, {}, 0);
    EndRun(c, w);
  }
  ExpectOk(c, "DMC-CFG-005", h.Call(dmc::MotorSetLimits{1, 0, 0, 0, 0, 0}));
  AtFrame(c, *u, 0, "DMC-RT-002");
}

}  // namespace moco::conformance::dmc_cases
