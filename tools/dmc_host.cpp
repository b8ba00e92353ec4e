// dmc-host: a small DMC v2 host for trying an emulated or real device by
// hand: connects to a PTY/serial path or a TCP port and plays a short
// Dragonframe-like session (HI, status, a move with its position updates,
// an upload, a live run with RT_END), printing every message both ways.
//   dmc-host /tmp/dmc16        dmc-host tcp:127.0.0.1:5000
#include <cstdio>
#include <cstdlib>
#include <string>

#include "transport/dmc_host_client.h"
#include "wire/dmc.h"

namespace {

namespace dmc = moco::dmc;
using moco::transport::testing::DeviceFrame;
using moco::transport::testing::DmcHostClient;

uint32_t next_id = 100;

void Print(const char* dir, uint32_t id, const std::string& text) {
  std::printf("%s #%u %s\n", dir, id, text.c_str());
}

// Sends `m`, prints it, and prints what comes back until its reply.
bool Exchange(DmcHostClient& c, const dmc::HostMessage& m, DeviceFrame* reply = nullptr) {
  const uint32_t id = next_id++;
  Print("host -> dev ", id, dmc::Describe(m));
  if (!c.Send(id, m)) return false;
  while (auto f = c.Next(3000)) {
    Print("dev  -> host", f->id, dmc::Describe(f->msg));
    if (f->id == id) {
      if (reply != nullptr) *reply = *f;
      return true;
    }
  }
  std::fprintf(stderr, "dmc-host: no reply to #%u within 3 s\n", id);
  return false;
}

// Prints unsolicited messages until `done` says so or nothing comes for 3 s.
template <typename Done>
bool Watch(DmcHostClient& c, Done done) {
  while (auto f = c.Next(3000)) {
    Print("dev  -> host", f->id, dmc::Describe(f->msg));
    if (done(*f)) return true;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  static constexpr const char* kUsage =
      "dmc-host: plays a short DMC v2 session against a device and prints it\n"
      "usage: dmc-host PATH | tcp:PORT | tcp:127.0.0.1:PORT\n"
      "Example: mocosim dmc16 --pty /tmp/dmc16 & dmc-host /tmp/dmc16\n";
  if (argc == 2 && std::string(argv[1]) == "--help") {
    std::fputs(kUsage, stdout);  // asked for: stdout, exit 0 (the man page is made from it)
    return 0;
  }
  if (argc != 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string target = argv[1];
  int fd = -1;
  if (target.rfind("tcp:", 0) == 0) {
    const std::string rest = target.substr(4);
    fd = moco::transport::testing::ConnectTcp(
        static_cast<uint16_t>(std::atoi(rest.substr(rest.rfind(':') + 1).c_str())));
  } else {
    fd = moco::transport::testing::OpenPtyHost(target);
  }
  if (fd < 0) {
    std::fprintf(stderr, "dmc-host: cannot open %s\n", target.c_str());
    return 1;
  }
  DmcHostClient c(fd);
  DeviceFrame hi;
  if (!Exchange(c, dmc::HiRequest{}, &hi)) return 1;
  if (!Exchange(c, dmc::MotorSetSpeed{1, 4000, 8000})) return 1;
  if (!Exchange(c, dmc::MotorMove{1, 2400})) return 1;
  const auto stopped = [](const DeviceFrame& f) {
    const auto* p = std::get_if<dmc::MotorPositionReport>(&f.msg);
    return p != nullptr && !p->positions_steps.empty() && p->positions_steps[0] == 2400;
  };
  if (!Watch(c, stopped)) return 1;
  if (!Exchange(c, dmc::MotorStatusRequest{})) return 1;
  // A 24-frame move of motor 1 from 2400 to 2400 + 23 * 20, played live at 24 fps.
  if (!Exchange(c, dmc::RtUploadMoveBegin{1, 24})) return 1;
  dmc::RtUploadMoveAxis axis{1, 0, true, {}};
  for (int32_t k = 0; k < 24; ++k) axis.positions_steps.push_back(2400 + 20 * k);
  if (!Exchange(c, axis)) return 1;
  if (!Exchange(c, dmc::RtUploadMoveEnd{})) return 1;
  dmc::RtRunMove run;
  run.fps_x1000 = 24000;
  run.start_frame = 1;
  run.end_frame = 24;
  run.preroll_ms = 500;
  run.postroll_ms = 500;
  if (!Exchange(c, run)) return 1;
  // Pre-roll: 480 steps/s reached over 0.5 s covers 120 steps, so the rig
  // waits for GO at 2280.
  const auto at_preroll = [](const DeviceFrame& f) {
    const auto* p = std::get_if<dmc::MotorPositionReport>(&f.msg);
    return p != nullptr && !p->positions_steps.empty() && p->positions_steps[0] == 2280;
  };
  if (!Watch(c, at_preroll)) return 1;
  if (!Exchange(c, dmc::RtGo{})) return 1;
  const auto ended = [](const DeviceFrame& f) { return std::holds_alternative<dmc::RtEnd>(f.msg); };
  if (!Watch(c, ended)) return 1;
  std::printf("session complete: %llu bad frame(s)\n",
              static_cast<unsigned long long>(c.bad_frames()));
  return c.bad_frames() == 0 ? 0 : 1;
}
