// Load test of served DMC-16s (the emulator's soak run): N devices in one
// process on PTYs and TCP ports, each driven by its own host at R requests/s
// for S seconds. Checks that no request is lost, reordered or unanswered and
// that memory stays flat; prints the numbers. Exit 0 when all hold.
//   dmc16_soak [--seconds 60] [--devices 8] [--rate 2000]
#include <malloc.h>
#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "transport/dmc_host_client.h"
#include "transport/serve.h"

namespace {

using moco::transport::testing::DmcHostClient;
using Clock = std::chrono::steady_clock;
namespace dmc = moco::dmc;

// Heap bytes in use (not RSS: glibc keeps freed memory of a busy moment, so
// RSS shows the peak backlog, while in-use bytes show what is still held).
long HeapInUseKiB() { return static_cast<long>(mallinfo2().uordblks / 1024); }

long RssKiB() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  return -1;
}

struct HostResult {
  uint64_t sent = 0;
  uint64_t answered = 0;
  uint64_t out_of_order = 0;
  uint64_t wrong_type = 0;
  uint64_t bad_frames = 0;
  bool io_error = false;
};

// Request i: HI, MOTOR_STATUS or MOTOR_GET_POSITION in turn.
dmc::HostMessage RequestFor(uint64_t i) {
  switch (i % 3) {
    case 0:
      return dmc::MotorStatusRequest{};
    case 1:
      return dmc::MotorGetPositionRequest{};
    default:
      return dmc::HiRequest{};
  }
}

void DriveHost(int fd, double seconds, int rate, HostResult& r) {
  constexpr uint32_t kFirstId = 0x10000;  // unsolicited frames use the device's own low IDs
  std::atomic<uint64_t> sent{0};
  std::atomic<bool> done{false};
  std::thread writer([&] {
    DmcHostClient client(fd);
    const auto t0 = Clock::now();
    const auto period = std::chrono::duration<double>(1.0 / rate);
    for (uint64_t i = 0;; ++i) {
      const auto due =
          t0 + std::chrono::duration_cast<Clock::duration>(period * static_cast<double>(i));
      if (std::chrono::duration<double>(due - t0).count() >= seconds) break;
      std::this_thread::sleep_until(due);
      if (!client.Send(kFirstId + static_cast<uint32_t>(i), RequestFor(i))) {
        r.io_error = true;
        break;
      }
      sent.store(i + 1);
    }
    done.store(true);
  });
  DmcHostClient reader(fd);
  uint64_t expect = 0;
  auto last_progress = Clock::now();
  for (;;) {
    auto f = reader.Next(200);
    if (!f) {
      if (done.load() &&
          (expect >= sent.load() || Clock::now() - last_progress > std::chrono::seconds(3))) {
        break;
      }
      continue;
    }
    if (f->id < kFirstId) continue;  // unsolicited (the power-on HI)
    last_progress = Clock::now();
    const uint64_t i = f->id - kFirstId;
    if (i != expect) ++r.out_of_order;
    expect = i + 1;
    ++r.answered;
    const uint16_t want = dmc::TypeOf(RequestFor(i));
    if (f->type != want) ++r.wrong_type;
  }
  writer.join();
  r.sent = sent.load();
  r.bad_frames = reader.bad_frames();
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 60;
  int devices = 8;
  int rate = 2000;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--seconds") {
      seconds = std::atof(argv[i + 1]);
    } else if (a == "--devices") {
      devices = std::atoi(argv[i + 1]);
    } else if (a == "--rate") {
      rate = std::atoi(argv[i + 1]);
    } else {
      std::fprintf(stderr, "usage: dmc16_soak [--seconds S] [--devices N] [--rate R]\n");
      return 2;
    }
  }
  if (seconds <= 0 || devices < 1 || devices > 64 || rate < 1) {
    std::fprintf(stderr, "dmc16_soak: need --seconds > 0, --devices 1..64, --rate >= 1\n");
    return 2;
  }
  const auto dir =
      std::filesystem::temp_directory_path() / ("moco_soak_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  moco::transport::EmulatorConfig config;
  config.log_level = moco::transport::LogLevel::kError;
  for (int d = 0; d < devices; ++d) {
    moco::transport::DeviceConfig c;
    c.model = "dmc16";
    c.name = "dmc16-" + std::to_string(d + 1);
    // Even devices on PTYs, odd on TCP. Pacing off: 2k requests/s need more
    // than a 115200-baud line carries.
    c.endpoint = d % 2 == 0 ? "pty:" + (dir / c.name).string() : "tcp:127.0.0.1:0";
    c.no_pacing = true;
    config.devices.push_back(c);
  }
  moco::transport::Emulator emulator(config, [](std::string_view l) {
    std::fprintf(stderr, "%.*s\n", static_cast<int>(l.size()), l.data());
  });
  emulator.Start();
  std::thread io([&] { emulator.Run(); });
  std::vector<int> fds;
  for (int d = 0; d < devices; ++d) {
    moco::transport::DeviceServer& s = emulator.server(static_cast<size_t>(d));
    const int fd = s.pty() != nullptr ? moco::transport::testing::OpenPtyHost(s.pty_path())
                                      : moco::transport::testing::ConnectTcp(s.tcp_port());
    if (fd < 0) {
      std::fprintf(stderr, "dmc16_soak: cannot open device %d: %s\n", d, std::strerror(errno));
      return 1;
    }
    fds.push_back(fd);
  }
  std::vector<HostResult> results(static_cast<size_t>(devices));
  std::vector<std::thread> hosts;
  long rss_start = 0;
  const auto t0 = Clock::now();
  for (int d = 0; d < devices; ++d) {
    hosts.emplace_back(DriveHost, fds[static_cast<size_t>(d)], seconds, rate,
                       std::ref(results[static_cast<size_t>(d)]));
  }
  // Memory after the first second (warm), and at the end.
  std::this_thread::sleep_for(
      std::chrono::milliseconds(std::min<int>(1000, static_cast<int>(seconds * 500))));
  rss_start = RssKiB();
  const long heap_start = HeapInUseKiB();
  for (auto& t : hosts) t.join();
  const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  const long rss_end = RssKiB();
  const long heap_end = HeapInUseKiB();
  for (int fd : fds) close(fd);
  moco::transport::asio::post(emulator.io(), [&] { emulator.Stop(); });
  io.join();
  std::filesystem::remove_all(dir);

  uint64_t sent = 0, answered = 0, ooo = 0, wrong = 0, bad = 0;
  bool io_error = false;
  for (const HostResult& r : results) {
    sent += r.sent;
    answered += r.answered;
    ooo += r.out_of_order;
    wrong += r.wrong_type;
    bad += r.bad_frames;
    io_error = io_error || r.io_error;
  }
  const uint64_t lost = sent - std::min(sent, answered);
  std::printf("dmc16 soak: %d devices (%d pty, %d tcp), %.1f s, target %d req/s each\n", devices,
              (devices + 1) / 2, devices / 2, elapsed, rate);
  std::printf(
      "  requests sent %llu (%.0f/s per device), answered %llu, lost %llu, reordered %llu, "
      "wrong type %llu, bad frames %llu\n",
      static_cast<unsigned long long>(sent), static_cast<double>(sent) / elapsed / devices,
      static_cast<unsigned long long>(answered), static_cast<unsigned long long>(lost),
      static_cast<unsigned long long>(ooo), static_cast<unsigned long long>(wrong),
      static_cast<unsigned long long>(bad));
  std::printf(
      "  heap in use after warm-up %ld KiB, at end %ld KiB (growth %ld KiB); RSS %ld -> %ld KiB\n",
      heap_start, heap_end, heap_end - heap_start, rss_start, rss_end);
  // Flat memory: nothing the run keeps grows with the number of requests (RSS
  // also holds the allocator's high-water mark of backlogs, so it is shown
  // but not judged).
  const bool flat = heap_end - heap_start < 1024;
  const bool ok = !io_error && lost == 0 && ooo == 0 && wrong == 0 && bad == 0 && flat;
  std::printf("  %s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}
