// Writes fixtures/sessions/dmc16-boom-move.jsonl: a DMC v2 host moving the
// boom rig of fixtures/profiles/dmc16-boom.json (docs/rig-dynamics.md
// "Plots") in virtual time: HI, MOTOR_SET_SPEED per joint motor, then one
// combined move of track, swing, boom, pan and tilt (MOTOR_MOVE each,
// dmc-v2-protocol.txt MSG_MOTOR_MOVE) and a status request at the end.
// `mocosim plot` and rig_plot_test.cpp plot it; the CTest
// plot_boom_session_fixture_is_current checks the file is this program's output.
//   cmake --build --preset dev --target boom_session_gen &&
//   build/dev/tools/session_gen/boom_session_gen fixtures/profiles/dmc16-boom.json
//   fixtures/sessions/dmc16-boom-move.jsonl  (one command line)
#include <cstdio>
#include <exception>
#include <string>

#include "devices/dmc16/dmc16.h"
#include "devices/dmc16/dmc16_profile.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "tools/session_gen/dmc16_script.h"
#include "wire/dmc.h"

namespace {

using namespace moco;

// One joint motor's move (motor numbers from dmc16-boom.json; steps from
// fixtures/rigs/boom-jib.json: 3200 microsteps per motor revolution times the
// gear ratio, per metre or per joint revolution).
struct JointMove {
  uint8_t motor;
  uint32_t speed_steps_per_s;
  uint32_t accel_steps_per_s2;
  int32_t target_steps;
};

// track: 160000 steps/m; swing: 800 steps/deg; boom, pan, tilt: 888.9 steps/deg.
constexpr JointMove kMoves[] = {
    {1, 16000, 16000, 64000},   // track 0.4 m at 0.1 m/s, 0.1 m/s^2: 1 + 3 + 1 s
    {2, 8000, 8000, -24000},    // swing -30 deg at 10 deg/s, 10 deg/s^2: 1 + 2 + 1 s
    {3, 4444, 4444, 13333},     // boom 15 deg at 5 deg/s, 5 deg/s^2: 1 + 2 + 1 s
    {4, 13333, 13333, -35556},  // pan -40 deg at 15 deg/s, 15 deg/s^2: 1 + 1.67 + 1 s
    {5, 4444, 4444, 8889},      // tilt 10 deg at 5 deg/s, 5 deg/s^2: 1 + 1 + 1 s
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: boom_session_gen PROFILE.json OUT.jsonl\n");
    return 2;
  }
  devices::Dmc16Profile profile;
  try {
    profile = devices::LoadDmc16Profile(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "boom_session_gen: %s\n", e.what());
    return 2;
  }
  const std::string note =
      "DMC-16 with fixtures/profiles/dmc16-boom.json (physical_rig: boom-jib), powered on at "
      "t = 0: HI, SET_SPEED of motors 1-5, then at 0.5 s one combined move: track (1) 0.4 m, "
      "swing (2) -30 deg (away from the light stand), boom (3) 15 deg, pan (4) -40 deg, "
      "tilt (5) 10 deg, 1 s ramps each, all at rest by 5.51 s; status at 6 s. Written by "
      "tools/session_gen/boom_session_gen.cpp";
  session_gen::Dmc16Script script(argv[2], note, std::move(profile), 2000);
  auto send = [&](sim::TimeNs t_ms, const dmc::HostMessage& m) {
    script.Send(t_ms * sim::kNsPerMs, m);
  };
  send(100, dmc::HiRequest{});
  sim::TimeNs t_ms = 200;
  for (const JointMove& j : kMoves) {
    send(t_ms, dmc::MotorSetSpeed{j.motor, j.speed_steps_per_s, j.accel_steps_per_s2});
    t_ms += 10;
  }
  t_ms = 500;
  for (const JointMove& j : kMoves) {
    send(t_ms, dmc::MotorMove{j.motor, j.target_steps});
    t_ms += 2;
  }
  send(6000, dmc::MotorStatusRequest{});
  const bool written = script.Finish(6100 * sim::kNsPerMs, "boom_session_gen");
  // The fixture is only useful if every request was accepted and every
  // motor reached its target.
  bool ok = script.device().stats().error_replies == 0;
  for (const JointMove& j : kMoves) {
    ok = ok && script.device().rig_ref().motor(j.motor).Position() == j.target_steps;
  }
  if (!written) return 1;
  if (!ok) {
    std::fprintf(stderr, "boom_session_gen: a request was refused or a motor missed its target\n");
    return 1;
  }
  return 0;
}
