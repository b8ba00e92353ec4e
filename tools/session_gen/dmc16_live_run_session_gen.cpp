// Writes fixtures/sessions/dmc16-live-run.jsonl: a live run at a low frame
// rate on the default DMC-16 in virtual time (docs/sessions.md), showing the
// position updates of dmc-v2-protocol.txt MSG_MOTOR_GET_POSITION ("about
// every 0.10 seconds, if any of the motors are moving") through the
// pre-roll, between the frames and in the post-roll, beside the report at
// each frame that MSG_RT_GO asks for. The replay tests
// (emulator/devices/session_replay_test.cpp, mococheck replay) check the
// device still answers it byte for byte and nanosecond for nanosecond.
//   cmake --build --preset dev --target dmc16_live_run_session_gen &&
//   build/dev/tools/session_gen/dmc16_live_run_session_gen fixtures/sessions/dmc16-live-run.jsonl
#include <cstdio>
#include <string>
#include <vector>

#include "devices/dmc16/dmc16.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "tools/session_gen/dmc16_script.h"
#include "wire/dmc.h"

int main(int argc, char** argv) {
  using namespace moco;
  if (argc != 2) {
    std::fprintf(stderr, "usage: dmc16_live_run_session_gen OUT.jsonl\n");
    return 2;
  }
  const std::string note =
      "Default DMC-16 (fixtures/profiles/dmc16.json), powered on at t = 0: HI, an upload of "
      "frames 10..40 (motor 1 climbs 40 steps a frame from 0, motor 2 holds 300, DMX channel 1 "
      "counts frames), POSITION_FRAME 12 (motor 1 to 80), RUN_MOVE 12..18 at 2 fps (80 steps/s) "
      "with 1500 ms pre-roll (start 80 - 80*1.5/2 = 20) and 1000 ms post-roll (320 + 40 = 360), "
      "SYNC DMX. GO at 2.0 s: updates every 100 ms in the pre-roll (MOVE TIME from 9000, the "
      "frame clock 3 frames before frame 12), a report at each frame 3.5 s + k * 0.5 s (MOVE "
      "TIME = frame x 1000), updates between them with fractions of a frame (MOTOR_GET_POSITION "
      "at 4.25 s answers 13500), then the post-roll (past 18000, 20000 at rest at 7.5 s) and "
      "RT_END";
  session_gen::Dmc16Script script(argv[1], note, devices::Dmc16Profile{}, 1000);
  auto send = [&](double t_s, const dmc::HostMessage& m) {
    script.Send(session_gen::Seconds(t_s), m);
  };
  send(0.1, dmc::HiRequest{});
  send(0.2, dmc::RtUploadMoveBegin{10, 40});
  dmc::RtUploadMoveAxis axis{1, 0, true, {}};
  std::vector<uint8_t> levels;
  for (int32_t k = 0; k <= 30; ++k) {
    axis.positions_steps.push_back(40 * k);
    levels.push_back(static_cast<uint8_t>(k));
  }
  send(0.3, axis);
  send(0.4, dmc::RtUploadMoveAxis{2, 0, true, {300}});
  send(0.5, dmc::RtUploadMoveDmx{1, 0, true, levels});
  send(0.6, dmc::RtUploadMoveEnd{});
  send(0.7, dmc::RtPositionFrame{12});
  dmc::RtRunMove run;
  run.fps_x1000 = 2000;
  run.start_frame = 12;
  run.end_frame = 18;
  run.preroll_ms = 1500;
  run.postroll_ms = 1000;
  run.sync_dmx = 1;
  send(1.5, run);
  send(2.0, dmc::RtGo{});
  send(4.25, dmc::MotorGetPositionRequest{});
  send(8.0, dmc::MotorStatusRequest{});
  return script.Finish(8500 * sim::kNsPerMs, "dmc16_live_run_session_gen") ? 0 : 1;
}
