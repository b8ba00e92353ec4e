// Request->response latency of a served DMC-16 over a real PTY and TCP
// (MSG_HI, MSG_MOTOR_STATUS), next to the raw echo round trip of the same
// transport measured in the same run; and the memory of a DMC-16 holding a
// full upload buffer; the DFMoco Arduino's reply latency, `mp` timing and
// memory per device. Pacing off unless noted: the transport and device cost.
//   device_bench [iterations]
#include <malloc.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "devices/dmc16/dmc16.h"
#include "devices/registry.h"
#include "serve/serve.h"
#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/test_support.h"
#include "wire/dfmoco.h"

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
  moco::serve::EmulatorConfig config;
  config.log_level = moco::serve::LogLevel::kError;
  moco::serve::DeviceConfig d;
  d.endpoint = spec;
  d.no_pacing = true;
  config.devices.push_back(d);
  moco::serve::Emulator emulator(config, [](std::string_view) {});
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
  const size_t heap_before = mallinfo2().uordblks;
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
      "complete=%d): store %zu KiB, device heap %zu KiB; process RSS %ld KiB (before the "
      "device %ld KiB)\n",
      frames, device.profile().motor_count, device.profile().dmx_channels,
      device.upload().complete() ? 1 : 0, device.upload().HeapBytes() / 1024,
      (mallinfo2().uordblks - heap_before) / 1024, after, before);
}

// Reads "\r\n" lines from fd; each with its arrival time.
class LineReader {
 public:
  explicit LineReader(int fd) : fd_(fd) {}
  // The next line within timeout_ms, or nullopt.
  std::optional<std::pair<Clock::time_point, std::string>> Next(int timeout_ms) {
    const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
    for (;;) {
      const size_t eol = buf_.find("\r\n");
      if (eol != std::string::npos) {
        std::string line = buf_.substr(0, eol);
        buf_.erase(0, eol + 2);
        return std::make_pair(arrived_, line);
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return std::nullopt;
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, static_cast<int>(left)) <= 0) continue;
      char tmp[512];
      const ssize_t r = read(fd_, tmp, sizeof tmp);
      if (r <= 0) return std::nullopt;
      arrived_ = Clock::now();
      buf_.append(tmp, static_cast<size_t>(r));
    }
  }

 private:
  int fd_;
  std::string buf_;
  Clock::time_point arrived_;
};

// The DFMoco Arduino over a PTY: `ms` reply latency (paced at its line,
// dfmoco::kBaudRate, and unpaced) and the timing of the once-a-second `mp`
// reports of a move.
void Dfmoco(const std::string& pty, int n) {
  const std::string baud = std::to_string(moco::dfmoco::kBaudRate);
  for (bool paced : {false, true}) {
    moco::serve::EmulatorConfig config;
    config.log_level = moco::serve::LogLevel::kError;
    moco::serve::DeviceConfig d;
    d.model = "dfmoco";
    d.endpoint = pty;
    d.no_pacing = !paced;
    config.devices.push_back(d);
    moco::serve::Emulator emulator(config, [](std::string_view) {});
    emulator.Start();
    std::thread t([&] { emulator.Run(); });
    const int fd = Open(emulator.server(0));
    LineReader lines(fd);
    if (!lines.Next(3000)) std::exit(1);  // the boot hi
    const std::string ms = "ms\r\n";
    std::vector<double> us;
    const int count = paced ? std::max(50, n / 10) : n;
    for (int i = -50; i < count; ++i) {
      const auto t0 = Clock::now();
      moco::transport::testing::WriteAll(fd, reinterpret_cast<const uint8_t*>(ms.data()),
                                         ms.size());
      auto l = lines.Next(3000);
      if (!l || l->second.rfind("ms ", 0) != 0) std::exit(1);
      if (i >= 0) us.push_back(std::chrono::duration<double, std::micro>(l->first - t0).count());
    }
    std::printf("dfmoco pty %-8s ms -> reply     median %7.1f  p99 %7.1f us\n",
                paced ? baud.c_str() : "unpaced", Median(us), P99(us));
    if (paced) {
      // A 6-second move: reports are due every second of the sketch's report
      // clock (0.5 s after its start, then every 1 s); compare their arrival
      // spacing with 1 s.
      const std::string mm = "pr 1 2000\r\nmm 1 10000\r\n";
      moco::transport::testing::WriteAll(fd, reinterpret_cast<const uint8_t*>(mm.data()),
                                         mm.size());
      std::vector<Clock::time_point> mp;
      while (auto l = lines.Next(3000)) {
        if (l->second.rfind("mp 1 ", 0) == 0) mp.push_back(l->first);
        if (l->second == "mp 1 10000") break;
      }
      std::vector<double> err_us;
      for (size_t i = 2; i + 1 < mp.size(); ++i) {
        const double spacing = std::chrono::duration<double, std::micro>(mp[i] - mp[i - 1]).count();
        err_us.push_back(std::abs(spacing - 1e6));
      }
      if (!err_us.empty()) {
        std::printf(
            "dfmoco pty %-8s mp spacing error vs 1 s: median %7.1f  max %7.1f us (%zu "
            "reports)\n",
            baud.c_str(), Median(err_us), *std::max_element(err_us.begin(), err_us.end()),
            mp.size());
      }
    }
    close(fd);
    asio::post(emulator.io(), [&] { emulator.Stop(); });
    t.join();
  }
  // Memory per device: 64 of a model in one process, in virtual time (heap
  // in use by the allocator, which RSS rounds to pages).
  for (const char* model : {"dfmoco", "stackshot3x", "dmc16"}) {
    const size_t before = mallinfo2().uordblks;
    moco::sim::Scheduler scheduler;
    NullSink sink;
    std::vector<std::unique_ptr<moco::devices::Device>> devices;
    for (int i = 0; i < 64; ++i) {
      devices.push_back(moco::devices::CreateDevice(model, "", scheduler, sink));
      devices.back()->PowerOn();
    }
    const size_t after = mallinfo2().uordblks;
    std::printf("%s memory: %.1f KiB heap per device, idle (64 devices)\n", model,
                static_cast<double>(after - before) / 64.0 / 1024.0);
  }
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
  Dfmoco(pty, n);
  return 0;
}
