// The latency `mocosim tap` adds (docs/benchmarks.md "Recording tap"): the
// round trip of a 12-byte frame (the size of a DMC HI request) to an echo
// device on a PTY, directly, and to a second one through a recording tap
// opening its PTY as the serial port, trips alternating so that both see the
// same machine load; unpaced (the tap's own cost against the
// fastest link there is) and paced at 115200 baud (a DMC-16's line).
//   tap_bench [iterations]
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "serve/tap.h"
#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/test_support.h"

namespace {

namespace asio = moco::transport::asio;
using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double P99(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, v.size() * 99 / 100)];
}

double RoundTrip(int fd) {
  static const moco::wire::Bytes frame(12, 0x5A);
  moco::wire::Bytes back(frame.size());
  const auto t0 = Clock::now();
  moco::transport::testing::WriteAll(fd, frame.data(), frame.size());
  size_t got = 0;
  while (got < back.size()) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 2000) <= 0) std::exit(1);
    const ssize_t r = read(fd, back.data() + got, back.size() - got);
    if (r <= 0) std::exit(1);
    got += static_cast<size_t>(r);
  }
  return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
}

// Alternates a trip on each path, so both see the same machine load.
void RoundTrips(const std::string& direct_pty, const std::string& tapped_pty, int n,
                std::vector<double>& direct, std::vector<double>& tapped) {
  const int a = moco::transport::testing::OpenPtyHost(direct_pty);
  const int b = moco::transport::testing::OpenPtyHost(tapped_pty);
  if (a < 0 || b < 0) std::exit(1);
  for (int i = -200; i < n; ++i) {
    const double da = RoundTrip(a);
    const double db = RoundTrip(b);
    if (i >= 0) {
      direct.push_back(da);
      tapped.push_back(db);
    }
  }
  close(a);
  close(b);
}

void Row(const char* what, const std::vector<double>& direct, const std::vector<double>& tapped) {
  std::printf("| %s | %.1f / %.1f us | %.1f / %.1f us | %.2f |\n", what, Median(direct),
              P99(direct), Median(tapped), P99(tapped), Median(tapped) / Median(direct));
}

// An echo device served on a PTY on its own io thread.
struct EchoServer {
  EchoServer(const std::string& path, bool paced) : driver(io, scheduler) {
    moco::transport::ServeOptions opts;
    opts.no_pacing = !paced;
    opts.log = [](std::string_view) {};
    server = std::make_unique<moco::transport::DeviceServer>(driver, "pty:" + path, opts);
    device = std::make_unique<moco::transport::testing::EchoDevice>(server->sink());
    server->Serve(*device);
    device->PowerOn();
    driver.Start();
    thread = std::thread([this] { io.run(); });
  }
  ~EchoServer() {
    asio::post(io, [this] {
      server->Stop();
      driver.Stop();
      io.stop();
    });
    thread.join();
  }
  asio::io_context io;
  moco::sim::Scheduler scheduler;
  moco::transport::RealtimeDriver driver;
  std::unique_ptr<moco::transport::DeviceServer> server;
  std::unique_ptr<moco::transport::testing::EchoDevice> device;
  std::thread thread;
};

void Measure(bool paced, int n) {
  const std::string dir =
      std::filesystem::temp_directory_path() / ("tap_bench." + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::vector<double> direct, tapped;
  {
    EchoServer direct_echo(dir + "/direct", paced);
    EchoServer behind_echo(dir + "/behind", paced);
    asio::io_context tap_io;
    moco::sim::Scheduler tap_scheduler;
    moco::transport::RealtimeDriver tap_driver(tap_io, tap_scheduler);
    moco::serve::TapConfig config;
    config.protocol = moco::wire::Protocol::kDmc;
    config.device = "serial:" + dir + "/behind";
    config.host = "pty:" + dir + "/host";
    config.record_path = dir + "/tapped.jsonl";
    auto tap = std::make_unique<moco::serve::Tap>(tap_driver, config, [](std::string_view) {});
    tap->Start();
    tap_driver.Start();
    std::thread tap_thread([&] { tap_io.run(); });
    RoundTrips(dir + "/direct", dir + "/host", n, direct, tapped);
    asio::post(tap_io, [&] {
      tap->Stop();
      tap_driver.Stop();
      tap_io.stop();
    });
    tap_thread.join();
  }
  std::filesystem::remove_all(dir);
  Row(paced ? "echo paced at 115200 baud, 12 B" : "echo unpaced, 12 B", direct, tapped);
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3000;
  std::printf("%d round trips after 200 warm-up ones\n\n", n);
  std::printf(
      "| device | direct median / p99 | through the tap (recording) median / p99 | ratio |\n");
  std::printf("| --- | --- | --- | --- |\n");
  Measure(false, n);
  Measure(true, n / 10 > 0 ? n / 10 : 1);
  return 0;
}
