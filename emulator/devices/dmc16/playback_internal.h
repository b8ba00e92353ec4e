// Helpers the DMC-16's playback engine shares across its files
// (playback.cpp, playback_requests.cpp, playback_tick.cpp), and the names
// those files use; internal to emulator/devices/dmc16, included by them only.
#ifndef MOCO_DEVICES_DMC16_PLAYBACK_INTERNAL_H_
#define MOCO_DEVICES_DMC16_PLAYBACK_INTERNAL_H_

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "sim/motion.h"
#include "sim/scheduler.h"
#include "wire/dmc.h"

namespace moco::devices::playback_internal {

using sim::TimeNs;

// Frame intervals planned per motor at a time during playback: bounds the
// plan's memory whatever the length of the move.
constexpr uint32_t kWindowFrames = 32;
constexpr double kNsPerSecondF = 1e9;

inline int Sign(double v) { return v > 0 ? 1 : (v < 0 ? -1 : 0); }

inline sim::Segment Seg(double duration_s, double v0, double a) {
  sim::Segment s;
  s.duration_s = duration_s;
  s.v0_steps_per_s = v0;
  s.a_steps_per_s2 = a;
  return s;
}

inline TimeNs CeilNs(double seconds) {
  return static_cast<TimeNs>(std::ceil(seconds * kNsPerSecondF));
}

inline uint32_t Intervals(uint32_t a, uint32_t b) { return a > b ? a - b : b - a; }

// MOVE TIME is a DWORD: before frame 0 it stays 0.
inline uint32_t ClampMoveTime(int64_t x1000) {
  return static_cast<uint32_t>(std::clamp<int64_t>(x1000, 0, int64_t{UINT32_MAX}));
}

// The velocity tick's conversion of a single-precision value to a whole
// number: truncation toward zero; not a number, and a value outside int32,
// give INT32_MIN, as on the reference firmware's measured (x86-64) build.
inline int32_t FirmwareInt(float v) {
  if (!(v > -2147483648.0f && v < 2147483648.0f)) return INT32_MIN;
  return static_cast<int32_t>(v);
}

// MOVE TIME of the tick's frame clock: the clock kept in 1/100000 frame
// (a whole number), reported in thousandths, each step in single precision.
inline uint32_t ClockX1000(float clock) {
  const float scaled = clock * 100000.0f;
  if (!(std::fabs(scaled) < 2147483648.0f)) return ClampMoveTime(std::llround(clock * 1000.0));
  const float x1000 = static_cast<float>(static_cast<int32_t>(scaled)) / 100.0f;
  return x1000 <= 0 ? 0 : static_cast<uint32_t>(x1000);
}

// The stills exposure of RUN_MOVE FLAGS 0x20, in fractions of a frame: from
// CAMERA OPEN ANGLE to CAMERA CLOSE ANGLE of its 360 degrees. Angles the
// device takes unchecked (behaviour.camera_angles_checked false) are read as
// dmc-lite reads them: CLOSE not above OPEN exposes 90 to 180 degrees, and
// the shutter stays open to the frame's end past 360.
inline std::pair<double, double> StillsExposure(const dmc::RtRunMove& m) {
  double open = m.camera_open_angle_deg.value_or(0);
  double close = m.camera_close_angle_deg.value_or(360);
  if (close <= open) {
    open = 90;
    close = 180;
  }
  return {std::min(open, 360.0) / 360.0, std::min(close, 360.0) / 360.0};
}

}  // namespace moco::devices::playback_internal

namespace moco::devices {

// The names the playback files use, declared once for the three of them.
using dmc::AckCode;
using playback_internal::CeilNs;
using playback_internal::ClampMoveTime;
using playback_internal::ClockX1000;
using playback_internal::FirmwareInt;
using playback_internal::Intervals;
using playback_internal::kNsPerSecondF;
using playback_internal::kWindowFrames;
using playback_internal::Seg;
using playback_internal::Sign;
using playback_internal::StillsExposure;
using sim::kNsPerMs;
using sim::TimeNs;

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_PLAYBACK_INTERNAL_H_
