// Request->response latency of a served DMC-16 over a real PTY and TCP
// (MSG_HI, MSG_MOTOR_STATUS), next to the raw echo round trip of the same
// transport measured in the same run; and the memory of a DMC-16 holding a
// full upload buffer. Pacing off: the transport and device cost alone.
//   device_bench [iterations]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "devices/dmc16/dmc16.h"
#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/serve.h"
#include "transport/test_support.h"

namespace {

namespace dmc = moco::dmc;
namespace asio = moco::transport::asio;
using moco::transport::testing::DmcHostClient;
using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double P99(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, v.size() * 99 / 100)];
}

int Open(moco::transport::DeviceServer& s) {
  return s.pty() != nullptr ? moco::transport::testing::OpenPtyHost(s.pty_path())
                            : moco::transport::testing::ConnectTcp(s.tcp_port());
}

// Raw echo of a 12-byte frame (the size of a HI request), read back the way
// the DMC host client reads replies.
std::vector<double> Echo(const std::string& spec, int n) {
  asio::io_context io;
  moco::sim::Scheduler scheduler;
  moco::transport::RealtimeDriver driver(io, scheduler);
  moco::transport::ServeOptions opts;
  opts.no_pacing = true;
  opts.log = [](std::string_view) {};
  moco::transport::DeviceServer server(driver, spec, opts);
  moco::transport::testing::EchoDevice device(server.sink());
  server.Serve(device);
  device.PowerOn();
  driver.Start();
  std::thread t([&] { io.run(); });
  const int fd = Open(server);
  moco::wire::Bytes frame = dmc::Encode(1, dmc::HostMessage{dmc::HiRequest{}});
  moco::wire::Bytes back(frame.size());
  std::vector<double> us;
  for (int i = -200; i < n; ++i) {
    const auto t0 = Clock::now();
    moco::transport::testing::WriteAll(fd, frame.data(), frame.size());
    size_t got = 0;
    while (got < back.size()) {
      // poll, then read: the same calls the DMC host client makes.
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 2000) <= 0) std::exit(1);
      const ssize_t r = read(fd, back.data() + got, back.size() - got);
      if (r <= 0) std::exit(1);
      got += static_cast<size_t>(r);
    }
    if (i >= 0) us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  }
  close(fd);
  asio::post(io, [&] {
    server.Stop();
    driver.Stop();
    io.stop();
  });
  t.join();
  return us;
}

// Request->response of a served DMC-16.
std::vector<double> Device(const std::string& spec, const dmc::HostMessage& request, int n) {
  moco::transport::EmulatorConfig config;
  config.log_level = moco::transport::LogLevel::kError;
  moco::transport::DeviceConfig d;
  d.endpoint = spec;
  d.no_pacing = true;
  config.devices.push_back(d);
  moco::transport::Emulator emulator(config, [](std::string_view) {});
  emulator.Start();
  std::thread t([&] { emulator.Run(); });
  const int fd = Open(emulator.server(0));
  DmcHostClient client(fd);
  std::vector<double> us;
  for (int i = -200; i < n; ++i) {
    const uint32_t id = 0x10000 + static_cast<uint32_t>(i + 200);
    const auto t0 = Clock::now();
    client.Send(id, request);
    if (!client.ReplyTo(id, 2000)) std::exit(1);
    if (i >= 0) us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
  }
  close(fd);
  asio::post(emulator.io(), [&] { emulator.Stop(); });
  t.join();
  return us;
}

long RssKiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  return -1;
}

class NullSink final : public moco::devices::ByteSink {
 public:
  void Write(moco::wire::ByteView) override {}
};

// A default DMC-16 (16 motors, 512 DMX channels, 10000 frames) with every
// frame of every motor and channel uploaded.
void Memory() {
  const long before = RssKiB();
  moco::sim::Scheduler scheduler;
  NullSink sink;
  moco::devices::Dmc16 device(scheduler, sink);
  device.PowerOn();
  const uint32_t frames = device.profile().upload_frame_count;
  uint32_t id = 1;
  auto send = [&](const dmc::HostMessage& m) { device.OnHostBytes(dmc::Encode(id++, m)); };
  send(dmc::RtUploadMoveBegin{0, frames - 1});
  for (uint8_t m = 1; m <= device.profile().motor_count; ++m) {
    for (uint32_t i = 0; i < frames; i += 250) {
      dmc::RtUploadMoveAxis a{m, i, i + 250 >= frames, {}};
      for (uint32_t k = i; k < std::min(frames, i + 250); ++k)
        a.positions_steps.push_back(static_cast<int32_t>(k));
      send(a);
    }
  }
  for (uint16_t ch = 1; ch <= device.profile().dmx_channels; ++ch) {
    for (uint32_t i = 0; i < frames; i += 1000) {
      dmc::RtUploadMoveDmx d{ch, i, i + 1000 >= frames,
                             std::vector<uint8_t>(std::min(frames, i + 1000) - i, 7)};
      send(d);
    }
  }
  send(dmc::RtUploadMoveEnd{});
  const long after = RssKiB();
  std::printf(
      "memory: DMC-16 with a full upload (%u frames x %u motors + %u DMX channels, "
      "complete=%d): store %zu KiB; process RSS %ld KiB (before the device %ld KiB)\n",
      frames, device.profile().motor_count, device.profile().dmx_channels,
      device.upload().complete() ? 1 : 0, device.upload().HeapBytes() / 1024, after, before);
}

}  // namespace

int main(int argc, char** argv) {
  int n = 3000;
  if (argc > 1 && argv[1][0] != '-') n = std::max(100, std::atoi(argv[1]));
  const std::string pty = "pty:" + (std::filesystem::temp_directory_path() /
                                    ("moco_dbench_" + std::to_string(getpid())))
                                       .string();
  std::printf(
      "request -> response, pacing off, n=%d (medians and p99 in us; ratio = median / echo "
      "median)\n",
      n);
  for (const std::string& spec : {pty, std::string("tcp:127.0.0.1:0")}) {
    const char* label = spec.rfind("pty:", 0) == 0 ? "pty" : "tcp";
    const auto echo = Echo(spec, n);
    const auto hi = Device(spec, dmc::HiRequest{}, n);
    const auto status = Device(spec, dmc::MotorStatusRequest{}, n);
    const double e = Median(echo);
    std::printf("%s raw echo 12 B      median %7.1f  p99 %7.1f\n", label, e, P99(echo));
    std::printf("%s dmc16 HI           median %7.1f  p99 %7.1f  ratio %.2f\n", label, Median(hi),
                P99(hi), Median(hi) / e);
    std::printf("%s dmc16 MOTOR_STATUS median %7.1f  p99 %7.1f  ratio %.2f\n", label,
                Median(status), P99(status), Median(status) / e);
  }
  Memory();
  return 0;
}
