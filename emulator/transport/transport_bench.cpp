// Round-trip latency of the transports (ARCHITECTURE "transport"): a host
// writes a small frame to a trivial echo device over a real PTY or a TCP
// connection on 127.0.0.1 and times until the echo is back. Pacing off, so
// this is the transport's own cost: the baseline for a device's
// request->response latency.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/test_support.h"
#include "wire/dmc_constants.h"

namespace {

using moco::transport::DeviceServer;
using moco::transport::RealtimeDriver;
using moco::transport::ServeOptions;
namespace asio = moco::transport::asio;
using Clock = std::chrono::steady_clock;

using moco::transport::testing::ConnectTcp;
using moco::transport::testing::OpenPtyHost;

bool WriteAll(int fd, const char* p, size_t n) {
  return moco::transport::testing::WriteAll(fd, reinterpret_cast<const uint8_t*>(p), n);
}

bool ReadAll(int fd, char* p, size_t n) {
  while (n > 0) {
    const ssize_t r = read(fd, p, n);
    if (r <= 0) return false;
    p += r;
    n -= static_cast<size_t>(r);
  }
  return true;
}

struct Stats {
  double median_us = 0;
  double p99_us = 0;
  double mean_us = 0;
  double max_us = 0;
};

Stats Summarize(std::vector<double> us) {
  std::sort(us.begin(), us.end());
  Stats s;
  s.median_us = us[us.size() / 2];
  s.p99_us = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  double sum = 0;
  for (double v : us) sum += v;
  s.mean_us = sum / static_cast<double>(us.size());
  s.max_us = us.back();
  return s;
}

// Times `iterations` echoes of a `frame_bytes` frame on fd (after a warm-up).
std::vector<double> RoundTrips(int fd, size_t frame_bytes, int iterations) {
  std::string frame(frame_bytes, '\0');
  for (size_t i = 0; i < frame_bytes; ++i) frame[i] = static_cast<char>('A' + i % 26);
  std::string back(frame_bytes, '\0');
  std::vector<double> us;
  for (int i = -200; i < iterations; ++i) {
    const auto t0 = Clock::now();
    if (!WriteAll(fd, frame.data(), frame.size()) || !ReadAll(fd, back.data(), back.size())) {
      std::fprintf(stderr, "transport_bench: I/O failed: %s\n", std::strerror(errno));
      std::exit(1);
    }
    const auto t1 = Clock::now();
    if (back != frame) {
      std::fprintf(stderr, "transport_bench: echo mismatch\n");
      std::exit(1);
    }
    if (i >= 0) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  return us;
}

// Serves an echo device on `spec` on an io thread and runs the round trips.
void Run(const std::string& label, const std::string& spec, bool pacing, size_t frame_bytes,
         int iterations) {
  asio::io_context io;
  moco::sim::Scheduler scheduler;
  RealtimeDriver driver(io, scheduler);
  ServeOptions opts;
  opts.no_pacing = !pacing;
  opts.log = [](std::string_view) {};
  DeviceServer server(driver, spec, opts);
  moco::transport::testing::EchoDevice device(server.sink());
  server.Serve(device);
  device.PowerOn();
  driver.Start();
  std::thread io_thread([&] { io.run(); });

  const int fd =
      server.pty() != nullptr ? OpenPtyHost(server.pty_path()) : ConnectTcp(server.tcp_port());
  if (fd < 0) {
    std::fprintf(stderr, "transport_bench: cannot open %s\n", spec.c_str());
    std::exit(1);
  }
  const Stats s = Summarize(RoundTrips(fd, frame_bytes, iterations));
  close(fd);
  asio::post(io, [&] {
    server.Stop();
    driver.Stop();
    io.stop();
  });
  io_thread.join();
  std::printf("%-28s %3zu B  n=%-6d median %8.1f us  p99 %8.1f us  mean %8.1f us  max %8.1f us\n",
              label.c_str(), frame_bytes, iterations, s.median_us, s.p99_us, s.mean_us, s.max_us);
}

}  // namespace

int main(int argc, char** argv) {
  int iterations = 5000;
  if (argc > 1) iterations = std::max(100, std::atoi(argv[1]));
  const std::string pty_path =
      (std::filesystem::temp_directory_path() / ("moco_bench_" + std::to_string(getpid())))
          .string();
  std::printf("echo round trip, host write -> device -> host read (pacing off unless noted)\n");
  for (size_t bytes : {1u, 16u, 64u}) {
    Run("pty echo", "pty:" + pty_path, false, bytes, iterations);
    Run("tcp echo (127.0.0.1)", "tcp:127.0.0.1:0", false, bytes, iterations);
  }
  // For scale: a paced line at a DMC v2 device's rate (16 B take 1.39 ms each
  // way at 115200 baud; an echo device answers byte by byte, so the two
  // directions overlap).
  Run("pty echo, paced " + std::to_string(moco::dmc::kBaudRate), "pty:" + pty_path, true, 16,
      std::max(100, iterations / 20));
  return 0;
}
