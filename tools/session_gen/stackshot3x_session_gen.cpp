// Writes fixtures/sessions/stackshot3x-workflow.jsonl: a typical StackShot
// host workflow against the default StackShot 3X in virtual time
// (docs/sessions.md): PING, ids, a speed setting, a 5 mm move polled every
// 100 ms as host tools do (FACTS), the position, a shutter fire, STOP. The
// replay test (emulator/devices/session_replay_test.cpp) checks the device
// still answers it byte for byte and nanosecond for nanosecond.
//   cmake --build --preset dev --target stackshot3x_session_gen &&
//   build/dev/tools/session_gen/stackshot3x_session_gen
//       fixtures/sessions/stackshot3x-workflow.jsonl   (one command line)
#include <cstdio>
#include <string>

#include "devices/stackshot3x/stackshot3x.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "tools/session_gen/device_recorder.h"
#include "wire/stackshot.h"

namespace {

using namespace moco;
using stackshot::Action;
using stackshot::Command;

stackshot::HostCommand Cmd(Command c, Action a, stackshot::Payload p = stackshot::Empty{}) {
  return stackshot::HostCommand{stackshot::Id(c), a, 0, false, false, std::move(p)};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: stackshot3x_session_gen OUT.jsonl\n");
    return 2;
  }
  session::SessionHeader h;
  h.protocol = wire::Protocol::kStackshot;
  h.device = "stackshot3x";
  h.clock = "virtual";
  h.note =
      "Default StackShot 3X (fixtures/profiles/stackshot3x.json), powered on at t = 0; host "
      "packets end in the constant checksum 0x69 (FACTS): PING 0x5A (answer 0xA5), software id, "
      "a move of 5 mm forward on X polled with CC_RAIL_STATUS every 100 ms, the position, one "
      "shutter pulse of 0.2 s (SHUTTER status bit set while it lasts), CC_RAIL_STOP";
  session::SessionWriter writer(argv[1], h);
  sim::Scheduler scheduler;
  session_gen::DeviceRecorder sink(scheduler, writer);
  devices::Stackshot3x device(scheduler, sink);
  device.PowerOn();
  auto send = [&](double t_s, const stackshot::HostCommand& c) {
    const auto t = static_cast<sim::TimeNs>(t_s * 1e9);
    scheduler.RunUntil(t);
    wire::Bytes bytes;
    stackshot::EncodeHostCommand(c, bytes, stackshot::ChecksumAlgorithm::kConstant69);
    sink.Host(bytes);
    device.OnHostBytes(bytes);
  };
  send(0.5, Cmd(Command::kPing, Action::kRead, stackshot::PingRequest{0x5A}));
  send(0.6, Cmd(Command::kSoftwareId, Action::kRead));
  send(0.7, Cmd(Command::kRailMove, Action::kWrite,
                stackshot::RailMove{stackshot::Direction::kForward, stackshot::Units::kMm, false,
                                    5.0f}));
  for (int i = 0; i < 30; ++i) send(0.8 + 0.1 * i, Cmd(Command::kRailStatus, Action::kRead));
  send(3.85, Cmd(Command::kRailPositionCurrent, Action::kRead));
  send(4.0, Cmd(Command::kRailShutterFire, Action::kWrite, stackshot::ShutterFire{1, 0.2f, 0.1f}));
  send(4.1, Cmd(Command::kRailStatus, Action::kRead));
  send(4.5, Cmd(Command::kRailStatus, Action::kRead));
  send(5.0, Cmd(Command::kRailStop, Action::kWrite));
  scheduler.RunUntil(6 * sim::kNsPerSecond);
  std::string error;
  if (!writer.Finish(&error)) {
    std::fprintf(stderr, "stackshot3x_session_gen: %s\n", error.c_str());
    return 1;
  }
  return 0;
}
