// One motor of the DFMoco 2.0.0 sketch as its main loop plans it (FACTS.md
// "DFMoco": Jog, Inch, Stop, Step generation, Planner), in the sketch's own
// single-precision arithmetic so that end positions match the real sketch to
// the step.
//
// The sketch plans a move as up to 7 constant-acceleration segments
// (calculatePointToPoint) and, once after every 50 ms chunk boundary
// (updateMotorVelocities), computes the next chunk: the integer position the
// plan reaches 50 ms further on, the step count `dx` to get there and the
// chunk speed `dx * 65.6` (clamped to 1..65535, the rate of the step
// generator's 16-bit phase accumulator). That chunk is stepped during the
// chunk after the next boundary, so `position` always leads the steps by up
// to two chunks. A chunk whose direction differs from the previous one's
// only turns the direction pin and is planned again one chunk later.
//
// SketchAxis holds that state and nothing else: no time. The device calls
// Update() once per chunk boundary and the command functions between them.
#ifndef MOCO_DEVICES_DFMOCO_ARDUINO_SKETCH_MOTION_H_
#define MOCO_DEVICES_DFMOCO_ARDUINO_SKETCH_MOTION_H_

#include <array>
#include <cstdint>

#include "sim/planner_dfmoco.h"

namespace moco::devices {

class SketchAxis {
 public:
  static constexpr int kSegments = 7;  // P2P_MOVE_COUNT
  // The sketch's velocity chunk (sim::kDfmocoChunkNs, 50 ms) in seconds.
  static constexpr float kChunkS = static_cast<float>(sim::kDfmocoChunkNs) / 1e9f;
  static_assert(kChunkS == 0.05f);
  // Steps per chunk -> chunk speed (the accumulator increment per 50 us).
  static constexpr float kSpeedPerStep = 65.6f;
  // Chunk speed -> steps/s: v = 20 * speed / 65.536.
  static constexpr float kSpeedToStepsPerS = 20.0f / 65.536f;

  // `pr`: maximum velocity v (already clamped to 100..20000) and maximum
  // acceleration v / 2.
  void SetPulseRate(int32_t steps_per_s);

  // updateMotorVelocities for this motor: plans the next chunk. Returns the
  // signed number of steps of that chunk (0 when it does not step).
  int32_t Update();

  // `mm` (and `bf`'s pre-positioning): destination = target; a new
  // point-to-point plan from the position and the loaded chunk's speed.
  void MoveTo(int32_t target);
  // stopMotor (`sm`, `sa`, `jm` against the motion, `im` while moving):
  // decelerate at the maximum acceleration from the loaded chunk's speed
  // (clamped to the maximum velocity), from `position`; the integer end is
  // computed once and becomes the destination. Nothing when destination ==
  // position.
  void Stop();
  // jogMotor with the 2.0.0 speed (0..10000 = 0..100 % of the pulse rate,
  // scaling velocity and acceleration). Speed 0 stops.
  void Jog(int32_t target, int32_t speed);
  // inchMotor: stops a motor whose loaded chunk steps; otherwise moves two
  // steps (planned over 10 ms) in the direction of target against the
  // *destination*, and sets the destination two steps on (clamped to target).
  void Inch(int32_t target);
  // `np`: the position counter only (the destination stays).
  void SetPosition(int32_t position) { position_ = position; }
  // Forgets any plan: at rest on `position` with destination = position.
  void Rest(int32_t position);

  int32_t position() const { return position_; }
  int32_t destination() const { return destination_; }
  bool moving() const { return moving_; }
  // Steps/s of the chunk planned last (signed).
  float LoadedVelocity() const;
  int32_t next_steps() const { return next_steps_; }

 private:
  // calculatePointToPoint with the given maxima.
  void PlanPointToPoint(int32_t target, float vmax, float amax);
  void ClearSegments();

  std::array<float, kSegments> move_time_{};
  std::array<int32_t, kSegments> move_position_{};
  std::array<float, kSegments> move_velocity_{};
  std::array<float, kSegments> move_accel_half_{};  // acceleration already halved
  int current_move_ = 0;
  float current_move_time_ = 0;
  bool forward_ = true;  // the direction pin
  bool moving_ = false;  // the motorMoving bit
  int32_t position_ = 0;
  int32_t destination_ = 0;
  float max_velocity_ = 5000;
  float max_accel_ = 2500;
  int32_t next_steps_ = 0;
  float next_speed_ = 0;  // dx * 65.6 clamped to 1..65535; 0 when the chunk does not step
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DFMOCO_ARDUINO_SKETCH_MOTION_H_
