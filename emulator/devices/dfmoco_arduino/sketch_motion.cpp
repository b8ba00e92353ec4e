// The DFMoco 2.0.0 sketch's per-motor planning (FACTS.md "DFMoco"); see
// sketch_motion.h. Every intermediate is a float, as on the AVR.
#include "devices/dfmoco_arduino/sketch_motion.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace moco::devices {
namespace {

// (int32_t)f: truncation towards zero; saturated where the AVR's conversion
// would overflow (and NaN gives 0) instead of undefined behaviour here.
int32_t Trunc32(float f) {
  if (!(f == f)) return 0;
  if (f >= 2147483520.0f) return std::numeric_limits<int32_t>::max();
  if (f <= -2147483648.0f) return std::numeric_limits<int32_t>::min();
  return static_cast<int32_t>(f);
}

// Signed distance, saturated to int32 (the sketch's int32 arithmetic).
int32_t Diff32(int32_t a, int32_t b) {
  const int64_t d = static_cast<int64_t>(a) - b;
  return static_cast<int32_t>(std::clamp<int64_t>(d, std::numeric_limits<int32_t>::min(),
                                                  std::numeric_limits<int32_t>::max()));
}

int32_t Add32(int32_t a, int64_t b) {
  return static_cast<int32_t>(std::clamp<int64_t>(a + b, std::numeric_limits<int32_t>::min(),
                                                  std::numeric_limits<int32_t>::max()));
}

}  // namespace

void SketchAxis::SetPulseRate(int32_t steps_per_s) {
  max_velocity_ = static_cast<float>(steps_per_s);
  max_accel_ = max_velocity_ * 0.5f;
}

float SketchAxis::LoadedVelocity() const {
  const float v = next_speed_ * kSpeedToStepsPerS;
  return forward_ ? v : -v;
}

void SketchAxis::ClearSegments() {
  move_time_.fill(0);
  move_velocity_.fill(0);
  move_accel_half_.fill(0);
  move_position_.fill(0);
}

void SketchAxis::Rest(int32_t position) {
  ClearSegments();
  current_move_ = 0;
  current_move_time_ = 0;
  moving_ = false;
  position_ = position;
  destination_ = position;
  next_steps_ = 0;
  next_speed_ = 0;
}

int32_t SketchAxis::Update() {
  next_steps_ = 0;
  next_speed_ = 0;
  if (!moving_) return 0;
  int seg = current_move_;
  if (seg >= kSegments || move_time_[static_cast<size_t>(seg)] == 0) {
    moving_ = false;
    return 0;
  }
  const float original_time = current_move_time_;
  const int original_move = current_move_;
  current_move_time_ += kChunkS;
  // One segment boundary at most per chunk (the sketch's single `if`).
  if (current_move_time_ >= move_time_[static_cast<size_t>(seg)]) {
    current_move_time_ -= move_time_[static_cast<size_t>(seg)];
    ++current_move_;
    ++seg;
  }
  if (seg >= kSegments) {  // cannot happen with the sketch's plans; stop safely
    moving_ = false;
    return 0;
  }
  const auto s = static_cast<size_t>(seg);
  const float t = current_move_time_;
  const int32_t xn = Trunc32(static_cast<float>(move_position_[s]) + move_velocity_[s] * t +
                             move_accel_half_[s] * t * t);
  const int32_t delta = Diff32(xn, position_);
  if (delta == 0) return 0;  // the direction pin changes only when stepping
  const bool forward = xn > position_;
  if (forward != forward_) {
    // Direction setup: this chunk only turns the pin; plan it again next time.
    current_move_time_ = original_time;
    current_move_ = original_move;
    forward_ = forward;
    return 0;
  }
  const auto dx = static_cast<float>(std::abs(static_cast<int64_t>(delta)));
  next_speed_ = std::max(1.0f, std::min(65535.0f, dx * kSpeedPerStep));
  next_steps_ = delta;
  position_ = xn;
  return delta;
}

void SketchAxis::MoveTo(int32_t target) {
  destination_ = target;
  if (target != position_) {
    PlanPointToPoint(target, max_velocity_, max_accel_);
    moving_ = true;
  }
}

void SketchAxis::PlanPointToPoint(int32_t target, float vmax, float amax) {
  ClearSegments();
  current_move_time_ = 0;
  move_position_[0] = position_;
  const float tmax = vmax / amax;
  const float dmax = vmax * tmax;
  float dist = std::fabs(static_cast<float>(Diff32(target, position_)));
  int dir = target > position_ ? 1 : -1;
  size_t n = 0;
  if (next_speed_ > 5) {  // blend with the velocity of the chunk already loaded
    const float vi = LoadedVelocity();
    const float ti = std::fabs(vi / amax);
    const float di = 0.5f * amax * ti * ti;
    if (vi * static_cast<float>(dir) < 0) {  // reversing: brake first
      move_time_[n] = ti;
      move_accel_half_[n] = static_cast<float>(dir) * amax;
      move_velocity_[n] = vi;
      ++n;
      dist += di;
    } else if (dist < di) {  // too close to stop: overshoot, then come back
      move_time_[n] = ti;
      move_accel_half_[n] = static_cast<float>(-dir) * amax;
      move_velocity_[n] = vi;
      ++n;
      dist = di - dist;
      dir = -dir;
    } else {  // further on: continue the ramp already under way
      dist += di;
      move_position_[0] =
          Trunc32(static_cast<float>(move_position_[0]) - static_cast<float>(dir) * di);
      current_move_time_ = ti;
    }
  }
  float t = tmax;
  if (dist <= dmax) t = std::sqrt(dist / amax);
  move_time_[n] = t;
  move_accel_half_[n] = static_cast<float>(dir) * amax;
  if (dist > dmax) {
    ++n;
    move_time_[n] = (dist - dmax) / vmax;
    move_accel_half_[n] = 0;
  }
  ++n;
  move_time_[n] = t;
  move_accel_half_[n] = static_cast<float>(-dir) * amax;
  for (size_t i = 1; i <= n; ++i) {
    const float ti = move_time_[i - 1];
    move_position_[i] =
        Trunc32(static_cast<float>(move_position_[i - 1]) + move_velocity_[i - 1] * ti +
                0.5f * move_accel_half_[i - 1] * ti * ti);
    move_velocity_[i] = move_velocity_[i - 1] + move_accel_half_[i - 1] * ti;
  }
  move_position_[n + 1] = target;
  for (size_t i = 0; i <= n; ++i) move_accel_half_[i] *= 0.5f;
  current_move_ = 0;
}

void SketchAxis::Stop() {
  if (destination_ == position_) return;
  ClearSegments();
  float v = next_speed_ * kSpeedToStepsPerS;
  if (v > max_velocity_) v = max_velocity_;
  if (!forward_) v = -v;
  const float a = v > 0 ? -max_accel_ : max_accel_;
  const float t = std::fabs(v / max_accel_);
  move_time_[0] = t;
  move_position_[0] = position_;
  move_velocity_[0] = v;
  move_accel_half_[0] = a * 0.5f;
  // The end, as an integer, once: the chunks step towards it and stop there.
  move_position_[1] = Trunc32(static_cast<float>(position_) + v * t + 0.5f * a * t * t);
  destination_ = move_position_[1];
  current_move_time_ = 0;
  current_move_ = 0;
  // A motor that was not stepping (t == 0) is taken off the moving list by
  // the next update, like the sketch's zero-length first segment.
}

void SketchAxis::Jog(int32_t target, int32_t speed) {
  if (speed <= 0) {
    Stop();
    return;
  }
  const float vi = LoadedVelocity();
  const int dir = target > position_ ? 1 : -1;
  // The sketch compares the boolean direction pin (1 forward, 0 reverse)
  // times dir with 0: only a forward motion is stopped by a backward jog.
  if (next_speed_ != 0 && (forward_ ? 1 : 0) * dir < 0) {
    Stop();
    return;
  }
  if (target == position_) return;
  const float scale = static_cast<float>(speed) / 10000.0f;
  const float vmax = max_velocity_ * scale;
  const float amax = max_accel_ * scale;
  // Accelerate for at most 0.5 s, cruise for the rest of those 0.5 s, brake.
  float accel_time = 0;
  float cruise_time = 0;
  if (std::fabs(vi) < vmax) {
    accel_time = (vmax - std::fabs(vi)) / amax;
    if (accel_time < 0.5f) {
      cruise_time = 0.5f - accel_time;
    } else {
      accel_time = 0.5f;
    }
  } else {
    cruise_time = 0.5f;
  }
  const float v_reached = std::fabs(vi) + amax * accel_time;
  int32_t delta = Trunc32(std::fabs(vi) * accel_time + 0.5f * amax * accel_time * accel_time);
  delta = Trunc32(static_cast<float>(delta) + cruise_time * v_reached);
  delta = Trunc32(static_cast<float>(delta) + 0.5f * (v_reached * v_reached) / amax);
  int32_t dest = Add32(position_, static_cast<int64_t>(dir) * delta);
  if ((dir == 1 && dest > target) || (dir == -1 && dest < target)) dest = target;
  // Each new jm extends the jog; the same destination leaves the plan alone.
  if (!moving_ || dest != destination_) {
    destination_ = dest;
    if (dest != position_) {
      PlanPointToPoint(dest, vmax, amax);
      moving_ = true;
    }
  }
}

void SketchAxis::Inch(int32_t target) {
  const int dir = target > destination_ ? 1 : -1;
  if (next_speed_ != 0) {
    Stop();
    return;
  }
  int32_t dest = Add32(destination_, 2 * dir);
  if ((dir == 1 && dest > target) || (dir == -1 && dest < target)) dest = target;
  ClearSegments();
  current_move_time_ = 0;
  move_time_[0] = 0.01f;  // two steps planned over 10 ms
  move_position_[0] = position_;
  move_position_[1] = Add32(position_, 2 * dir);
  current_move_ = 0;
  destination_ = dest;
  if (dest != position_) moving_ = true;
}

}  // namespace moco::devices
