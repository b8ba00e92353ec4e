// What a host reading an emulated StackShot 3X over a PTY sees of each reply,
// with and without the USB serial bridge model (devices/usb_bridge.h,
// docs/profiles.md "usb_bridge"), while the machine is busy. A host that
// honours the StackShot's 2 ms inter-frame rule (stackshot-protocol.txt
// section 2) drops a reply whose bytes arrive with a longer gap in the
// middle; a real FTDI chip never makes one, since it sends the reply in one
// USB packet. For each bridge the host asks CC_RAIL_STATUS `replies` times,
// one request every `interval` to 2 x `interval` ms, reading each reply with poll() and read()
// and timing every piece; `load` threads spin meanwhile. The bridges are
// served side by side and asked in turn, so all see the same machine.
//   bridge_gap_bench [replies] [load-threads] [interval-ms]
// Prints, per bridge: replies read, replies in more than one piece, replies
// with a gap above 2 ms and above 3 ms between two pieces, those of them the
// bridge did not make (a gap more than 2 ms from its timer's period: an FTDI
// chip splits a reply that straddles its latency tick, the pieces one period
// apart, as the hardware does), the longest gap, and the
// median and 99th percentile from request to whole reply.
#include <poll.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "serve/serve.h"
#include "transport/asio.h"
#include "transport/dmc_host_client.h"
#include "wire/stackshot.h"

namespace {

namespace asio = moco::transport::asio;
using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

double Percentile(std::vector<double> v, int pct) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, v.size() * static_cast<size_t>(pct) / 100)];
}

double Load1() {
  double load[1] = {0};
  return getloadavg(load, 1) == 1 ? load[0] : -1;
}

struct Result {
  int replies = 0;
  int pieces_over_one = 0;
  int gap_over_2ms = 0;
  int gap_over_3ms = 0;
  int not_the_bridges = 0;  // a gap > 3 ms no tick of the bridge explains
  double max_gap_ms = 0;
  std::vector<double> latency_ms;
};

// One StackShot served on a PTY by the emulator, on its own io thread.
class Served {
 public:
  Served(const std::string& pty, const std::string& profile) {
    moco::serve::EmulatorConfig config;
    config.log_level = moco::serve::LogLevel::kError;
    moco::serve::DeviceConfig d;
    d.model = "stackshot3x";
    d.endpoint = "pty:" + pty;
    d.profile_path = profile;
    d.state_path = pty + ".state.json";
    config.devices.push_back(d);
    emulator_ = std::make_unique<moco::serve::Emulator>(config, [](std::string_view) {});
    emulator_->Start();
    thread_ = std::thread([this] { emulator_->Run(); });
  }
  ~Served() {
    asio::post(emulator_->io(), [this] { emulator_->Stop(); });
    thread_.join();
  }

 private:
  std::unique_ptr<moco::serve::Emulator> emulator_;
  std::thread thread_;
};

// Whether a gap between two pieces of a reply is one a bridge with this
// timer period makes (0: no bridge, every gap is the host's or the load's):
// consecutive packets of one reply leave at consecutive ticks, one period
// apart, so a gap more than 2 ms from the period is not the bridge's.
bool BridgeMade(double gap_ms, double period_ms) {
  return period_ms > 0 && std::abs(gap_ms - period_ms) <= 2.0;
}

// The host end of one served StackShot, asking CC_RAIL_STATUS and timing
// each piece of the reply.
class Host {
 public:
  Host(const std::string& pty, double period_ms) : period_ms_(period_ms) {
    fd_ = moco::transport::testing::OpenPtyHost(pty);
    if (fd_ < 0) {
      std::perror("open pty");
      std::exit(1);
    }
    moco::stackshot::HostCommand status;
    status.command = static_cast<uint16_t>(moco::stackshot::Command::kRailStatus);
    status.action = moco::stackshot::Action::kRead;
    moco::stackshot::EncodeHostCommand(status, request_);
  }
  ~Host() { close(fd_); }
  Host(const Host&) = delete;
  Host& operator=(const Host&) = delete;

  void Trip() {
    // A CC_RAIL_STATUS read response: header, u32 status, checksum.
    constexpr size_t kReplyBytes = 10;
    const auto t0 = Clock::now();
    if (!moco::transport::testing::WriteAll(fd_, request_.data(), request_.size())) std::exit(1);
    size_t got = 0;
    std::vector<Clock::time_point> pieces;
    while (got < kReplyBytes) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 2000) <= 0) {
        std::fprintf(stderr, "no reply within 2 s\n");
        std::exit(1);
      }
      const ssize_t n = read(fd_, buf_.data(), buf_.size());
      if (n <= 0) std::exit(1);
      got += static_cast<size_t>(n);
      pieces.push_back(Clock::now());
    }
    double gap = 0;
    bool unexplained = false;
    for (size_t k = 1; k < pieces.size(); ++k) {
      const double g = Ms(pieces[k] - pieces[k - 1]);
      gap = std::max(gap, g);
      if (g > 3.0 && !BridgeMade(g, period_ms_)) unexplained = true;
    }
    Result& r = result;
    r.not_the_bridges += unexplained ? 1 : 0;
    ++r.replies;
    r.pieces_over_one += pieces.size() > 1 ? 1 : 0;
    r.gap_over_2ms += gap > 2.0 ? 1 : 0;
    r.gap_over_3ms += gap > 3.0 ? 1 : 0;
    r.max_gap_ms = std::max(r.max_gap_ms, gap);
    r.latency_ms.push_back(Ms(pieces.back() - t0));
  }

  Result result;

 private:
  int fd_ = -1;
  double period_ms_;
  moco::wire::Bytes request_;
  std::array<uint8_t, 256> buf_{};
};

}  // namespace

int main(int argc, char** argv) {
  const int replies = argc > 1 ? std::atoi(argv[1]) : 1000;
  const int load_threads = argc > 2 ? std::atoi(argv[2]) : 4;
  const int interval_ms = argc > 3 ? std::atoi(argv[3]) : 20;
  if (replies <= 0 || load_threads < 0 || interval_ms <= 0) {
    std::fprintf(stderr, "usage: bridge_gap_bench [replies>0] [load-threads>=0] [interval-ms>0]\n");
    return 2;
  }
  const fs::path dir = fs::temp_directory_path() / ("bridge_gap_bench." + std::to_string(getpid()));
  fs::create_directories(dir);
  struct Bridge {
    const char* name;
    const char* field;
    double period_ms;
  };
  const Bridge bridges[] = {
      {"none (each byte as the UART ends it)", R"("none")", 0},
      {"ftdi, 16 ms (the default)", R"("ftdi")", 16},
      {"ftdi, 1 ms latency", R"({"kind": "ftdi", "latency_ms": 1})", 1},
  };
  std::atomic<bool> stop{false};
  std::vector<std::thread> load;
  for (int i = 0; i < load_threads; ++i) {
    load.emplace_back([&stop] {
      volatile uint64_t x = 0;
      while (!stop.load(std::memory_order_relaxed)) x = x + 1;
    });
  }
  std::printf(
      "%d replies per bridge, one CC_RAIL_STATUS every %d..%d ms, %d spinning threads, %u cores\n",
      replies, interval_ms, 2 * interval_ms, load_threads, std::thread::hardware_concurrency());
  std::printf(
      "| bridge | replies | in >1 piece | gap > 2 ms | gap > 3 ms | gap > 3 ms not the bridge's | "
      "longest gap | reply p50 | reply p99 |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  // Every bridge served at once, one request to each in turn (the first
  // rotating), so all see the same machine.
  std::vector<std::unique_ptr<Served>> served;
  std::vector<std::unique_ptr<Host>> hosts;
  for (size_t i = 0; i < std::size(bridges); ++i) {
    const fs::path profile = dir / ("p" + std::to_string(i) + ".json");
    std::ofstream(profile) << R"({"device": "stackshot3x", "usb_bridge": )" << bridges[i].field
                           << "}\n";
    const std::string pty = (dir / ("ss" + std::to_string(i))).string();
    served.push_back(std::make_unique<Served>(pty, profile.string()));
    for (int tries = 0; tries < 200 && !fs::exists(pty); ++tries) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    hosts.push_back(std::make_unique<Host>(pty, bridges[i].period_ms));
  }
  std::mt19937 rng(1205);
  std::uniform_int_distribution<int> jitter(0, interval_ms * 1000);
  const double load_before = Load1();
  for (int i = 0; i < replies; ++i) {
    for (size_t k = 0; k < hosts.size(); ++k) {
      const auto t0 = Clock::now();
      hosts[(static_cast<size_t>(i) + k) % hosts.size()]->Trip();
      // A pause of interval..2*interval ms (seeded), so requests fall at
      // every phase of the bridges' timers, not at one the interval aliases.
      const auto pause = std::chrono::microseconds(interval_ms * 1000 + jitter(rng));
      std::this_thread::sleep_until(t0 + pause);
    }
  }
  for (size_t i = 0; i < hosts.size(); ++i) {
    const Result& r = hosts[i]->result;
    const auto pct = [&](int n) { return 100.0 * n / r.replies; };
    std::printf(
        "| %s | %d | %d (%.1f%%) | %d (%.1f%%) | %d (%.1f%%) | %d (%.1f%%) | %.2f ms | %.2f ms | "
        "%.2f ms |\n",
        bridges[i].name, r.replies, r.pieces_over_one, pct(r.pieces_over_one), r.gap_over_2ms,
        pct(r.gap_over_2ms), r.gap_over_3ms, pct(r.gap_over_3ms), r.not_the_bridges,
        pct(r.not_the_bridges), r.max_gap_ms, Percentile(r.latency_ms, 50),
        Percentile(r.latency_ms, 99));
  }
  std::printf("load average %.1f before, %.1f after\n", load_before, Load1());
  hosts.clear();
  served.clear();
  stop = true;
  for (auto& t : load) t.join();
  fs::remove_all(dir);
  return 0;
}
