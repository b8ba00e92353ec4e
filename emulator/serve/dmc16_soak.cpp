// Load test of served DMC-16s (the emulator's soak run): N devices in one
// process on PTYs and TCP ports, each driven by its own host for S seconds,
// either at R requests/s on unpaced lines, or (--pacing) on lines paced at the
// device's baud rate with the host writing up to A requests ahead in writes of
// up to 500 requests (far more than the line carries: the host outruns it).
// Checks that every request is answered exactly once and in order (none lost,
// repeated, reordered or invented), that memory stays flat, and with --record
// that every device's recording decodes without a problem (as `mocosim decode
// --strict`); prints the numbers. Exit 0 when all hold.
//   dmc16_soak [--seconds 60] [--devices 8] [--rate 2000]
//   dmc16_soak --pacing [--ahead 2000] [--record] [--seconds 60] [--devices 8]
#include <malloc.h>
#include <sys/resource.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "serve/serve.h"
#include "session/session.h"
#include "transport/dmc_host_client.h"
#include "wire/transcript.h"

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
  uint64_t out_of_order = 0;  // an answer to a later request before an earlier one's
  uint64_t duplicated = 0;    // a second answer to a request already answered
  uint64_t invented = 0;      // an answer to a request never sent
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

constexpr uint32_t kFirstId = 0x10000;  // unsolicited frames use the device's own low IDs

// Reads answers until the writer is done and every request is answered (or
// nothing arrived for 3 s), judging each against the requests sent.
void ReadAnswers(int fd, const std::atomic<uint64_t>& sent, const std::atomic<bool>& done,
                 std::atomic<uint64_t>& answered, HostResult& r) {
  DmcHostClient reader(fd);
  std::vector<bool> seen;
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
    if (i >= sent.load()) {
      ++r.invented;
      continue;
    }
    if (i >= seen.size()) seen.resize(i + 1 + 4096, false);
    if (seen[i]) {
      ++r.duplicated;
      continue;
    }
    seen[i] = true;
    if (i != expect) ++r.out_of_order;
    expect = i + 1;
    ++r.answered;
    answered.store(r.answered);
    if (f->type != dmc::TypeOf(RequestFor(i))) ++r.wrong_type;
  }
  r.bad_frames = reader.bad_frames();
}

// At `rate` requests/s, one request per write.
void DriveHostAtRate(int fd, double seconds, int rate, HostResult& r) {
  std::atomic<uint64_t> sent{0};
  std::atomic<uint64_t> answered{0};
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
      sent.store(i + 1);  // before the bytes leave: an answer may come back at once
      if (!client.Send(kFirstId + static_cast<uint32_t>(i), RequestFor(i))) {
        sent.store(i);
        r.io_error = true;
        break;
      }
    }
    done.store(true);
  });
  ReadAnswers(fd, sent, done, answered, r);
  writer.join();
  r.sent = sent.load();
}

// As far ahead as `ahead` unanswered requests, in writes of up to 500.
void DriveHostAhead(int fd, double seconds, uint64_t ahead, HostResult& r) {
  constexpr uint64_t kMaxBurst = 500;
  std::atomic<uint64_t> sent{0};
  std::atomic<uint64_t> answered{0};
  std::atomic<bool> done{false};
  std::thread writer([&] {
    const auto end = Clock::now() + std::chrono::duration<double>(seconds);
    moco::wire::Bytes burst;
    uint64_t i = 0;
    while (Clock::now() < end) {
      const uint64_t outstanding = i - answered.load();
      if (outstanding >= ahead) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        continue;
      }
      const uint64_t n = std::min(kMaxBurst, ahead - outstanding);
      burst.clear();
      for (uint64_t k = 0; k < n; ++k) {
        dmc::Encode(kFirstId + static_cast<uint32_t>(i + k), RequestFor(i + k), burst);
      }
      i += n;
      sent.store(i);
      if (!moco::transport::testing::WriteAll(fd, burst.data(), burst.size())) {
        r.io_error = true;
        break;
      }
    }
    done.store(true);
  });
  ReadAnswers(fd, sent, done, answered, r);
  writer.join();
  r.sent = sent.load();
}

// Problems `mocosim decode --strict` would count in a recording; -1 when it
// cannot be read.
long RecordingProblems(const std::filesystem::path& path, size_t* entries) {
  auto loaded = moco::session::LoadSession(path);
  const auto* session = std::get_if<moco::session::Session>(&loaded);
  if (session == nullptr) return -1;
  *entries = session->entries.size();
  moco::wire::TranscriptDecoder decoder(session->header.protocol);
  long problems = 0;
  auto count = [&](const std::vector<moco::wire::TranscriptLine>& lines) {
    for (const auto& l : lines) problems += l.problem ? 1 : 0;
  };
  for (const auto& e : session->entries) {
    if (e.is_event) continue;
    count(decoder.Feed(e.from == moco::session::Origin::kHost ? moco::wire::Side::kHost
                                                              : moco::wire::Side::kDevice,
                       e.bytes));
  }
  count(decoder.Finish());
  if (!moco::session::SessionWarning(*session).empty()) ++problems;
  return problems;
}

}  // namespace

int Usage() {
  std::fprintf(
      stderr,
      "usage: dmc16_soak [--seconds S] [--devices N] [--rate R]\n"
      "       dmc16_soak --pacing [--ahead A] [--record] [--seconds S] [--devices N]\n"
      "  --rate R    unpaced lines, R requests/s per device, one per write (default 2000)\n"
      "  --pacing    lines paced at the device's baud rate; the host writes up to A\n"
      "              unanswered requests ahead (default 2000), up to 500 per write\n"
      "  --record    record every device's session and decode each strictly\n");
  return 2;
}

// A whole number in [lo, hi], or nullopt.
std::optional<long> Whole(const char* text, long lo, long hi) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text, &end, 10);
  if (errno != 0 || end == text || *end != '\0' || v < lo || v > hi) return std::nullopt;
  return v;
}

// The command line.
struct SoakArgs {
  double seconds = 60;
  long devices = 8;
  long rate = 2000;
  long ahead = 2000;
  bool pacing = false;
  bool record = false;
};

// Reads the command line into `args`; the exit status when it is wrong.
std::optional<int> ParseArgs(int argc, char** argv, SoakArgs& args) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--pacing") {
      args.pacing = true;
      continue;
    }
    if (a == "--record") {
      args.record = true;
      continue;
    }
    if (i + 1 >= argc) return Usage();
    const char* v = argv[++i];
    std::optional<long> n;
    if (a == "--seconds") {
      char* end = nullptr;
      args.seconds = std::strtod(v, &end);
      if (end == v || *end != '\0' || !(args.seconds > 0 && args.seconds <= 86400)) {
        std::fprintf(stderr, "dmc16_soak: --seconds takes a number in (0, 86400]\n");
        return 2;
      }
      continue;
    }
    if (a == "--devices") {
      n = Whole(v, 1, 64);
      if (n) args.devices = *n;
    } else if (a == "--rate") {
      n = Whole(v, 1, 1'000'000);
      if (n) args.rate = *n;
    } else if (a == "--ahead") {
      n = Whole(v, 1, 1'000'000);
      if (n) args.ahead = *n;
    } else {
      return Usage();
    }
    if (!n) {
      std::fprintf(stderr,
                   "dmc16_soak: %s takes a whole number (devices 1..64, rate and ahead "
                   "1..1000000)\n",
                   a.c_str());
      return 2;
    }
  }
  return std::nullopt;
}

// The emulator's devices: `args.devices` DMC-16s, recorded in `dir` with
// --record.
moco::serve::EmulatorConfig SoakConfig(const SoakArgs& args, const std::filesystem::path& dir) {
  moco::serve::EmulatorConfig config;
  config.log_level = moco::serve::LogLevel::kError;
  for (long d = 0; d < args.devices; ++d) {
    moco::serve::DeviceConfig c;
    c.model = "dmc16";
    c.name = "dmc16-" + std::to_string(d + 1);
    // Even devices on PTYs, odd on TCP. Unpaced at a fixed rate: 2k
    // requests/s need more than a 115200-baud line carries.
    c.endpoint = d % 2 == 0 ? "pty:" + (dir / c.name).string() : "tcp:127.0.0.1:0";
    c.no_pacing = !args.pacing;
    if (args.record) c.record_path = (dir / (c.name + ".jsonl")).string();
    config.devices.push_back(c);
  }
  return config;
}

// The time the hosts took and the memory in use after the first second (warm)
// and at the end.
struct Measured {
  double elapsed = 0;
  long rss_start = 0, rss_end = 0, heap_start = 0, heap_end = 0;
};

// Drives each device (`fds`) from a host thread of its own until every host
// is done, each result in `results`.
Measured DriveHosts(const SoakArgs& args, const std::vector<int>& fds,
                    std::vector<HostResult>& results) {
  Measured m;
  std::vector<std::thread> hosts;
  const auto t0 = Clock::now();
  for (long d = 0; d < args.devices; ++d) {
    HostResult& r = results[static_cast<size_t>(d)];
    const int fd = fds[static_cast<size_t>(d)];
    if (args.pacing) {
      hosts.emplace_back(DriveHostAhead, fd, args.seconds, static_cast<uint64_t>(args.ahead),
                         std::ref(r));
    } else {
      hosts.emplace_back(DriveHostAtRate, fd, args.seconds, static_cast<int>(args.rate),
                         std::ref(r));
    }
  }
  std::this_thread::sleep_for(
      std::chrono::milliseconds(std::min<int>(1000, static_cast<int>(args.seconds * 500))));
  m.rss_start = RssKiB();
  m.heap_start = HeapInUseKiB();
  for (auto& t : hosts) t.join();
  m.elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
  m.rss_end = RssKiB();
  m.heap_end = HeapInUseKiB();
  return m;
}

// The problems of every device's recording, decoded strictly; their entries
// are added to `entries`.
long RecordingsProblems(const moco::serve::EmulatorConfig& config, size_t* entries) {
  long problems = 0;
  for (const auto& c : config.devices) {
    size_t n = 0;
    const long p = RecordingProblems(c.record_path, &n);
    if (p < 0) {
      std::printf("  recording %s cannot be read\n", c.record_path.c_str());
      ++problems;
      continue;
    }
    problems += p;
    *entries += n;
  }
  return problems;
}

// Prints the numbers and the verdict; the exit status (0 when all hold).
int Report(const SoakArgs& args, const std::vector<HostResult>& results, const Measured& m,
           long recording_problems, size_t recorded_entries) {
  HostResult all;
  for (const HostResult& r : results) {
    all.sent += r.sent;
    all.answered += r.answered;
    all.out_of_order += r.out_of_order;
    all.duplicated += r.duplicated;
    all.invented += r.invented;
    all.wrong_type += r.wrong_type;
    all.bad_frames += r.bad_frames;
    all.io_error = all.io_error || r.io_error;
  }
  const long devices = args.devices;
  const uint64_t lost = all.sent - std::min(all.sent, all.answered);
  if (args.pacing) {
    std::printf(
        "dmc16 soak: %ld devices (%ld pty, %ld tcp), %.1f s, paced lines, host up to "
        "%ld requests ahead\n",
        devices, (devices + 1) / 2, devices / 2, m.elapsed, args.ahead);
  } else {
    std::printf("dmc16 soak: %ld devices (%ld pty, %ld tcp), %.1f s, target %ld req/s each\n",
                devices, (devices + 1) / 2, devices / 2, m.elapsed, args.rate);
  }
  auto u = [](uint64_t v) { return static_cast<unsigned long long>(v); };
  std::printf(
      "  requests sent %llu (%.0f/s per device), answered %llu, lost %llu, reordered %llu, "
      "duplicated %llu, invented %llu, wrong type %llu, bad frames %llu\n",
      u(all.sent), static_cast<double>(all.sent) / m.elapsed / static_cast<double>(devices),
      u(all.answered), u(lost), u(all.out_of_order), u(all.duplicated), u(all.invented),
      u(all.wrong_type), u(all.bad_frames));
  if (args.record) {
    std::printf("  recordings: %zu entries, %ld problem(s) decoding strictly\n", recorded_entries,
                recording_problems);
  }
  std::printf(
      "  heap in use after warm-up %ld KiB, at end %ld KiB (growth %ld KiB); RSS %ld -> %ld KiB\n",
      m.heap_start, m.heap_end, m.heap_end - m.heap_start, m.rss_start, m.rss_end);
  // Flat memory: nothing the run keeps grows with the number of requests (RSS
  // also holds the allocator's high-water mark of backlogs, so it is shown
  // but not judged). Recordings are streamed to disk, so they count too.
  const bool flat = m.heap_end - m.heap_start < 1024;
  const bool ok = !all.io_error && all.sent > 0 && lost == 0 && all.out_of_order == 0 &&
                  all.duplicated == 0 && all.invented == 0 && all.wrong_type == 0 &&
                  all.bad_frames == 0 && recording_problems == 0 && flat;
  std::printf("  %s\n", ok ? "PASS" : "FAIL");
  return ok ? 0 : 1;
}

int main(int argc, char** argv) {
  SoakArgs args;
  if (const auto exit_code = ParseArgs(argc, argv, args)) return *exit_code;
  const auto dir =
      std::filesystem::temp_directory_path() / ("moco_soak_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  const moco::serve::EmulatorConfig config = SoakConfig(args, dir);
  auto emulator = std::make_unique<moco::serve::Emulator>(config, [](std::string_view l) {
    std::fprintf(stderr, "%.*s\n", static_cast<int>(l.size()), l.data());
  });
  emulator->Start();
  std::thread io([&] { emulator->Run(); });
  std::vector<int> fds;
  for (long d = 0; d < args.devices; ++d) {
    moco::transport::DeviceServer& s = emulator->server(static_cast<size_t>(d));
    const int fd = s.pty() != nullptr ? moco::transport::testing::OpenPtyHost(s.pty_path())
                                      : moco::transport::testing::ConnectTcp(s.tcp_port());
    if (fd < 0) {
      std::fprintf(stderr, "dmc16_soak: cannot open device %ld: %s\n", d, std::strerror(errno));
      return 1;
    }
    fds.push_back(fd);
  }
  std::vector<HostResult> results(static_cast<size_t>(args.devices));
  const Measured m = DriveHosts(args, fds, results);
  for (int fd : fds) close(fd);
  moco::transport::asio::post(emulator->io(), [&] { emulator->Stop(); });
  io.join();
  emulator.reset();  // finishes the recordings

  size_t recorded_entries = 0;
  const long recording_problems = args.record ? RecordingsProblems(config, &recorded_entries) : 0;
  std::filesystem::remove_all(dir);
  return Report(args, results, m, recording_problems, recorded_entries);
}
