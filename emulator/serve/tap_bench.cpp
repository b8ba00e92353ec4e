// The latency `mocosim tap` adds (docs/benchmarks.md "Recording tap"). Four
// identical devices, each served on its own PTY on its own io thread, are
// reached by one host each way:
//   direct        host -> device PTY
//   bare relay    host -> PTY -> a minimal forwarder (poll, read, write;
//                 nothing else) -> device PTY: the floor, two more PTY hops
//   tap           host -> the tap's PTY -> `mocosim tap` recording -> device PTY
//   tap, no rec.  the same tap without a recording
// one round trip on each in turn (the first path rotating), so that all four
// see the same machine load. Devices: an echo of a 12-byte frame (a DMC HI
// request's size) and an emulated DMC-16 answering MSG_HI (dmc-v2-protocol.txt
// "MSG_HI [0x0001]"; 12 bytes out, 63 back), each unpaced (the tap's own cost against the
// fastest link there is) and paced at a DMC-16's line (dmc::kBaudRate).
//   tap_bench [iterations]
// and flow control with a slow side (docs/tap.md "Flow control"): a device
// sending BYTES to a host that reads nothing until the tap holds the device
// back, then everything; and a host writing BYTES ahead of a device that
// reads nothing until the tap holds the host back. Each prints the bytes
// sent, delivered and recorded (counted in the session file) and the most the
// tap held at once:
//   tap_bench slow-reader [bytes]
#include <poll.h>
#include <pthread.h>
#include <pty.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "serve/serve.h"
#include "serve/tap.h"
#include "session/session.h"
#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/test_support.h"
#include "wire/dmc_constants.h"

namespace {

namespace asio = moco::transport::asio;
namespace dmc = moco::dmc;
using Clock = std::chrono::steady_clock;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
double P99(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, v.size() * 99 / 100)];
}

double Load1() {
  double load[1] = {0};
  return getloadavg(load, 1) == 1 ? load[0] : -1;
}

void Name(std::thread& t, const char* name) { pthread_setname_np(t.native_handle(), name); }

// A device served on a PTY on its own io thread.
class Served {
 public:
  virtual ~Served() = default;
};

class EchoServer final : public Served {
 public:
  EchoServer(const std::string& path, bool paced) : driver_(io_, scheduler_) {
    moco::transport::ServeOptions opts;
    opts.no_pacing = !paced;
    opts.log = [](std::string_view) {};
    server_ = std::make_unique<moco::transport::DeviceServer>(driver_, "pty:" + path, opts);
    device_ = std::make_unique<moco::transport::testing::EchoDevice>(server_->sink());
    server_->Serve(*device_);
    device_->PowerOn();
    driver_.Start();
    thread_ = std::thread([this] { io_.run(); });
    Name(thread_, "echo");
  }
  ~EchoServer() override {
    asio::post(io_, [this] {
      server_->Stop();
      driver_.Stop();
      io_.stop();
    });
    thread_.join();
  }

 private:
  asio::io_context io_;
  moco::sim::Scheduler scheduler_;
  moco::transport::RealtimeDriver driver_;
  std::unique_ptr<moco::transport::DeviceServer> server_;
  std::unique_ptr<moco::transport::testing::EchoDevice> device_;
  std::thread thread_;
};

// An emulated DMC-16, as `mocosim dmc16 --pty PATH [--no-pacing]` serves it.
class Dmc16Server final : public Served {
 public:
  Dmc16Server(const std::string& path, bool paced) {
    moco::serve::EmulatorConfig config;
    config.log_level = moco::serve::LogLevel::kError;
    moco::serve::DeviceConfig d;
    d.endpoint = "pty:" + path;
    d.no_pacing = !paced;
    config.devices.push_back(d);
    emulator_ = std::make_unique<moco::serve::Emulator>(config, [](std::string_view) {});
    emulator_->Start();
    thread_ = std::thread([this] { emulator_->Run(); });
    Name(thread_, "dmc16");
  }
  ~Dmc16Server() override {
    asio::post(emulator_->io(), [this] { emulator_->Stop(); });
    thread_.join();
  }

 private:
  std::unique_ptr<moco::serve::Emulator> emulator_;
  std::thread thread_;
};

// The least a forwarder between two PTYs can do: one thread polling both
// ends, reading what is there and writing it to the other end. No recording,
// no event loop, no timers: what remains of the tap's cost is the two PTY
// hops and the wake-ups they take.
class BareRelay {
 public:
  BareRelay(const std::string& device_path, const std::string& link_path) : link_(link_path) {
    char name[256] = {};
    int slave = -1;
    if (openpty(&master_, &slave, name, nullptr, nullptr) != 0) std::exit(1);
    termios t{};
    tcgetattr(slave, &t);
    cfmakeraw(&t);
    tcsetattr(slave, TCSANOW, &t);
    slave_ = slave;
    std::filesystem::remove(link_);
    std::filesystem::create_symlink(name, link_);
    device_ = moco::transport::testing::OpenPtyHost(device_path);
    if (device_ < 0 || pipe(stop_) != 0) std::exit(1);
    thread_ = std::thread([this] { Run(); });
    Name(thread_, "relay");
  }
  ~BareRelay() {
    const char c = 0;
    (void)write(stop_[1], &c, 1);
    thread_.join();
    for (int fd : {master_, slave_, device_, stop_[0], stop_[1]}) close(fd);
    std::filesystem::remove(link_);
  }

 private:
  void Run() {
    std::array<uint8_t, 4096> buf{};
    for (;;) {
      pollfd p[3] = {{master_, POLLIN, 0}, {device_, POLLIN, 0}, {stop_[0], POLLIN, 0}};
      if (poll(p, 3, -1) < 0) continue;
      if (p[2].revents != 0) return;
      for (int i = 0; i < 2; ++i) {
        if ((p[i].revents & POLLIN) == 0) continue;
        const ssize_t n = read(p[i].fd, buf.data(), buf.size());
        if (n > 0) {
          moco::transport::testing::WriteAll(i == 0 ? device_ : master_, buf.data(),
                                             static_cast<size_t>(n));
        }
      }
    }
  }
  std::string link_;
  int master_ = -1;
  int slave_ = -1;
  int device_ = -1;
  int stop_[2] = {-1, -1};
  std::thread thread_;
};

// A tap on its own io thread, recording when record_path is given.
class TapRunner {
 public:
  TapRunner(const std::string& device_path, const std::string& host_path,
            const std::string& record_path)
      : driver_(io_, scheduler_) {
    moco::serve::TapConfig config;
    config.protocol = moco::wire::Protocol::kDmc;
    config.device = "serial:" + device_path;
    config.host = "pty:" + host_path;
    config.record_path = record_path;
    tap_ = std::make_unique<moco::serve::Tap>(driver_, config, [](std::string_view) {});
    tap_->Start();
    driver_.Start();
    thread_ = std::thread([this] { io_.run(); });
    Name(thread_, "tap");
  }
  ~TapRunner() {
    asio::post(io_, [this] {
      tap_->Stop();
      driver_.Stop();
      io_.stop();
    });
    thread_.join();
  }

 private:
  asio::io_context io_;
  moco::sim::Scheduler scheduler_;
  moco::transport::RealtimeDriver driver_;
  std::unique_ptr<moco::serve::Tap> tap_;
  std::thread thread_;
};

// One host on one path: a round trip, in microseconds.
class Host {
 public:
  virtual ~Host() = default;
  virtual double Trip() = 0;
};

// Writes a 12-byte frame and reads it back: poll, then read, the calls the
// DMC host client makes.
class EchoHost final : public Host {
 public:
  explicit EchoHost(int fd) : fd_(fd) {}
  ~EchoHost() override { close(fd_); }
  double Trip() override {
    static const moco::wire::Bytes frame(12, 0x5A);
    moco::wire::Bytes back(frame.size());
    const auto t0 = Clock::now();
    moco::transport::testing::WriteAll(fd_, frame.data(), frame.size());
    size_t got = 0;
    while (got < back.size()) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 2000) <= 0) std::exit(1);
      const ssize_t r = read(fd_, back.data() + got, back.size() - got);
      if (r <= 0) std::exit(1);
      got += static_cast<size_t>(r);
    }
    return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
  }

 private:
  int fd_;
};

// MSG_HI and its reply, as a host sees a device's answer.
class HiHost final : public Host {
 public:
  explicit HiHost(int fd) : fd_(fd), client_(fd) {}
  ~HiHost() override { close(fd_); }
  double Trip() override {
    const uint32_t id = ++id_;
    const auto t0 = Clock::now();
    client_.Send(id, dmc::HostMessage{dmc::HiRequest{}});
    if (!client_.ReplyTo(id, 2000)) std::exit(1);
    return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
  }

 private:
  int fd_;
  moco::transport::testing::DmcHostClient client_;
  uint32_t id_ = 1000;
};

enum class Kind { kEcho, kDmc16 };
constexpr int kPaths = 4;
const char* const kPathNames[kPaths] = {"direct", "bare relay (floor)", "tap, recording",
                                        "tap, not recording"};

void Measure(Kind kind, bool paced, int n, int warmup) {
  const std::string dir =
      std::filesystem::temp_directory_path() / ("tap_bench." + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  std::array<std::vector<double>, kPaths> us;
  const double load_before = Load1();
  {
    std::vector<std::unique_ptr<Served>> devices;
    for (int i = 0; i < kPaths; ++i) {
      const std::string path = dir + "/device" + std::to_string(i);
      if (kind == Kind::kEcho) {
        devices.push_back(std::make_unique<EchoServer>(path, paced));
      } else {
        devices.push_back(std::make_unique<Dmc16Server>(path, paced));
      }
    }
    BareRelay relay(dir + "/device1", dir + "/relay");
    TapRunner tap(dir + "/device2", dir + "/tap", dir + "/tapped.jsonl");
    TapRunner tap_unrecorded(dir + "/device3", dir + "/tap-unrecorded", "");
    const std::string host_paths[kPaths] = {dir + "/device0", dir + "/relay", dir + "/tap",
                                            dir + "/tap-unrecorded"};
    std::vector<std::unique_ptr<Host>> hosts;
    for (const std::string& p : host_paths) {
      const int fd = moco::transport::testing::OpenPtyHost(p);
      if (fd < 0) std::exit(1);
      if (kind == Kind::kEcho) {
        hosts.push_back(std::make_unique<EchoHost>(fd));
      } else {
        hosts.push_back(std::make_unique<HiHost>(fd));
      }
    }
    for (int i = -warmup; i < n; ++i) {
      const int first = (i + warmup) % kPaths;
      for (int k = 0; k < kPaths; ++k) {
        const int path = (first + k) % kPaths;
        const double t = hosts[path]->Trip();
        if (i >= 0) us[path].push_back(t);
      }
    }
  }
  std::filesystem::remove_all(dir);
  const std::string device = std::string(kind == Kind::kEcho ? "echo 12 B" : "DMC-16 HI") +
                             (paced ? ", paced at " + std::to_string(moco::dmc::kBaudRate) + " baud"
                                    : std::string(", unpaced"));
  const double direct = Median(us[0]);
  for (int p = 0; p < kPaths; ++p) {
    std::printf("| %s | %s | %.1f / %.1f us | %+.1f us | %.2f |\n", device.c_str(), kPathNames[p],
                Median(us[p]), P99(us[p]), Median(us[p]) - direct, Median(us[p]) / direct);
  }
  std::fprintf(stderr, "  %s: load average %.2f before, %.2f after\n", device.c_str(), load_before,
               Load1());
}

}  // namespace

// One side floods, the other reads nothing until the tap holds the flood
// back, then reads all of it.
struct SlowReaderResult {
  size_t sent = 0;
  size_t delivered = 0;  // what the slow side read, equal to what was sent
  size_t recorded = 0;   // that direction's bytes in the session file
  size_t lost_events = 0;
  bool held = false;     // the tap held the fast side back
  size_t peak_held = 0;  // the most the tap held for the slow side
  moco::serve::TapStats stats;
};

SlowReaderResult SlowReader(bool device_floods, size_t bytes) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("tap_bench.slow." + std::to_string(getpid()));
  fs::create_directories(dir);
  int device_fd = -1;
  int slave = -1;
  char slave_name[256] = {};
  if (openpty(&device_fd, &slave, slave_name, nullptr, nullptr) != 0) std::abort();
  close(slave);
  asio::io_context io;
  moco::sim::Scheduler scheduler;
  moco::transport::RealtimeDriver driver(io, scheduler);
  moco::serve::TapConfig config;
  config.protocol = moco::wire::Protocol::kDmc;
  config.device = std::string("serial:") + slave_name;
  config.host = "pty:" + (dir / "host").string();
  config.record_path = (dir / "s.jsonl").string();
  auto tap = std::make_unique<moco::serve::Tap>(driver, config, [](std::string_view) {});
  tap->Start();
  driver.Start();
  std::thread tap_thread([&] { io.run(); });
  const int host_fd = moco::transport::testing::OpenPtyHost((dir / "host").string());
  auto on_tap = [&](auto f) {
    std::promise<decltype(f())> result;
    auto future = result.get_future();
    asio::post(io, [&] { result.set_value(f()); });
    return future.get();
  };
  SlowReaderResult r;
  r.sent = bytes;
  std::vector<uint8_t> sent(bytes);
  for (size_t i = 0; i < bytes; ++i) sent[i] = static_cast<uint8_t>(i * 7 + i / 251);
  const int from = device_floods ? device_fd : host_fd;
  const int to = device_floods ? host_fd : device_fd;
  std::atomic<bool> written{false};
  std::thread writer([&] {
    moco::transport::testing::WriteAll(from, sent.data(), sent.size());
    written = true;
  });
  for (int i = 0; i < 20000 && !r.held && !written; ++i) {
    r.held = on_tap([&] { return device_floods ? tap->device_held() : tap->host_held(); });
    if (!r.held) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  std::vector<uint8_t> got;
  std::vector<uint8_t> buf(65536);
  while (got.size() < bytes) {
    pollfd p{to, POLLIN, 0};
    if (poll(&p, 1, 10000) <= 0) break;
    const ssize_t n = read(to, buf.data(), std::min(buf.size(), bytes - got.size()));
    if (n <= 0) break;
    got.insert(got.end(), buf.begin(), buf.begin() + n);
  }
  writer.join();
  r.delivered = got == sent ? got.size() : 0;
  asio::post(io, [&] {
    tap->Stop();
    r.stats = tap->stats();
    driver.Stop();
    io.stop();
  });
  tap_thread.join();
  r.peak_held = device_floods ? r.stats.peak_to_host_bytes : r.stats.peak_to_device_bytes;
  auto loaded = moco::session::LoadSession(config.record_path);
  if (const auto* s = std::get_if<moco::session::Session>(&loaded)) {
    for (const auto& e : s->entries) {
      if (e.is_event) {
        if (e.event.value("event", "") == "lost") ++r.lost_events;
      } else if ((e.from == moco::session::Origin::kDevice) == device_floods) {
        r.recorded += e.bytes.size();
      }
    }
  }
  close(host_fd);
  close(device_fd);
  fs::remove_all(dir);
  return r;
}

int SlowReaderMain(size_t bytes) {
  std::printf("load average %.2f\n\n", Load1());
  std::printf(
      "| slow side | sent | delivered | recorded | lost events | held back | most held in the tap "
      "|\n| --- | --- | --- | --- | --- | --- | --- |\n");
  int rc = 0;
  for (bool device_floods : {true, false}) {
    const SlowReaderResult r = SlowReader(device_floods, bytes);
    std::printf("| %s | %zu | %zu | %zu | %zu | %s | %zu |\n",
                device_floods ? "host (device sends)" : "device (host sends)", r.sent, r.delivered,
                r.recorded, r.lost_events, r.held ? "yes" : "no", r.peak_held);
    if (r.sent != r.delivered || r.sent != r.recorded || r.lost_events != 0) rc = 1;
  }
  return rc;
}

int main(int argc, char** argv) {
  if (argc > 1 && std::string(argv[1]) == "slow-reader") {
    return SlowReaderMain(argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 1'000'000);
  }
  const int n = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3000;
  const int paced_n = std::max(1, n / 10);
  std::printf(
      "%d round trips per path unpaced, %d paced, after warm-up ones; load average %.2f\n\n", n,
      paced_n, Load1());
  std::printf("| device | path | median / p99 | median over direct | ratio |\n");
  std::printf("| --- | --- | --- | --- | --- |\n");
  Measure(Kind::kEcho, false, n, 200);
  Measure(Kind::kEcho, true, paced_n, 20);
  Measure(Kind::kDmc16, false, n, 200);
  Measure(Kind::kDmc16, true, paced_n, 20);
  return 0;
}
