// Writes fixtures/sessions/dmc16-workflow.jsonl: a typical DMC v2 host
// workflow against the default DMC-16 in virtual time (docs/sessions.md).
// The replay test (dmc16_replay_test.cpp) checks the device still answers it
// byte for byte and nanosecond for nanosecond. Values checked by hand are
// listed in the session's note.
//   cmake --build --preset dev --target dmc16_session_gen &&
//   build/dev/tools/session_gen/dmc16_session_gen fixtures/sessions/dmc16-workflow.jsonl
#include <cstdio>
#include <string>
#include <vector>

#include "devices/dmc16/dmc16.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "tools/session_gen/dmc16_script.h"
#include "wire/dmc.h"

namespace {

using namespace moco;

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: dmc16_session_gen OUT.jsonl\n");
    return 2;
  }
  const std::string note =
      "Default DMC-16 (fixtures/profiles/dmc16.json), powered on at t = 0: HI, SET_SPEED "
      "4000/8000, a move of motor 1 to 2400 (0.5 s ramps + 0.1 s cruise: 1.1 s, updates every "
      "100 ms, 40 steps at 0.1 s), status, RESET_POSITION, motor 17 (ERR_RANGE), a damaged "
      "frame (ERR_CHECKSUM), an unknown type (ERR_UNSUPPORTED), a 24-frame upload, RUN_MOVE "
      "at 24 fps with 500 ms pre/post-roll (pre-roll start 2400 - 480*0.5/2 = 2280), GO with "
      "a report per frame and updates every 100 ms in the pre-roll (MOVE TIME 0: the frame "
      "clock before frame 0) and the post-roll (MOVE TIME past frame 24, 36000 at rest), "
      "RT_END after the post-roll (2860 + 120 = 2980)";
  session_gen::Dmc16Script script(argv[1], note, devices::Dmc16Profile{}, 1000);
  auto send = [&](double t_s, const dmc::HostMessage& m) {
    script.Send(session_gen::Seconds(t_s), m);
  };
  send(0.5, dmc::HiRequest{});
  send(0.6, dmc::MotorSetSpeed{1, 4000, 8000});
  send(0.7, dmc::MotorMove{1, 2400});
  send(2.0, dmc::MotorStatusRequest{});
  send(2.1, dmc::MotorResetPosition{2, 100});
  send(2.2, dmc::MotorMove{17, 5});
  wire::Bytes damaged = script.Encode(dmc::MotorStop{1});
  damaged[10] ^= 0x40;
  script.SendBytes(2300 * sim::kNsPerMs, damaged);
  send(2.4, dmc::Unknown{0x0077, {}});
  send(2.5, dmc::RtUploadMoveBegin{1, 24});
  dmc::RtUploadMoveAxis axis{1, 0, true, {}};
  for (int32_t k = 0; k < 24; ++k) axis.positions_steps.push_back(2400 + 20 * k);
  send(2.6, axis);
  send(2.7, dmc::RtUploadMoveEnd{});
  dmc::RtRunMove run;
  run.fps_x1000 = 24000;
  run.start_frame = 1;
  run.end_frame = 24;
  run.preroll_ms = 500;
  run.postroll_ms = 500;
  send(2.8, run);
  send(3.5, dmc::RtGo{});
  send(6.0, dmc::MotorStatusRequest{});
  return script.Finish(7 * sim::kNsPerSecond, "dmc16_session_gen") ? 0 : 1;
}
