// mocosim tap: following a StackShot's switch to its DfMoco dialect from the
// traffic (stackshot-protocol.txt 1.1.17 CC_RAIL_CONFIG_GLOBAL_MODE, section
// 3; ERRATA 3.7) and the device-side specs it takes.
#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <pty.h>

#include <atomic>
#include <filesystem>
#include <future>
#include <string>
#include <thread>
#include <variant>

#include "serve/tap.h"
#include "serve/tap_line_rate.h"
#include "session/session.h"
#include "transport/device_server.h"
#include "transport/dmc_host_client.h"
#include "transport/test_support.h"
#include "wire/stackshot.h"
#include "wire/stackshot_constants.h"

namespace moco::serve {
namespace {

using stackshot::Action;
using stackshot::Command;
using stackshot::GlobalMode;

wire::Bytes ModeWrite(GlobalMode mode) {
  stackshot::HostCommand c;
  c.command = static_cast<uint16_t>(Command::kRailConfigGlobalMode);
  c.action = Action::kWrite;
  c.payload = stackshot::EnumValue<GlobalMode>{mode};
  wire::Bytes out;
  EXPECT_TRUE(stackshot::EncodeHostCommand(c, out));
  return out;
}

wire::Bytes ModeAnswer(Action status) {
  stackshot::DeviceReply r;
  r.command = static_cast<uint16_t>(Command::kRailConfigGlobalMode);
  r.status = status;
  r.kind =
      status == Action::kRspOk ? stackshot::ReplyKind::kWriteAck : stackshot::ReplyKind::kError;
  r.payload = stackshot::Empty{};
  wire::Bytes out;
  EXPECT_TRUE(stackshot::EncodeDeviceReply(r, out));
  return out;
}

TEST(LineRateFollower, AcknowledgedDfmocoModeSwitchesTo57600AfterTheAck) {
  LineRateFollower f(wire::Protocol::kStackshot);
  f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
  // The request alone switches nothing: the device answers at the old rate.
  EXPECT_EQ(f.dialect(), wire::Protocol::kStackshot);
  const auto change = f.OnDeviceBytes(ModeAnswer(Action::kRspOk));
  ASSERT_TRUE(change.has_value());
  EXPECT_EQ(change->baud, 57600u);
  EXPECT_EQ(change->dialect, wire::Protocol::kStackshotDfmoco);
  EXPECT_EQ(f.dialect(), wire::Protocol::kStackshotDfmoco);
  // DfMoco text from then on is not read as packets.
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
}

TEST(LineRateFollower, SwitchIsFoundInAnyChunking) {
  const wire::Bytes req = ModeWrite(GlobalMode::kMotionDfMoco);
  const wire::Bytes ack = ModeAnswer(Action::kRspOk);
  for (size_t cut = 0; cut <= ack.size(); ++cut) {
    LineRateFollower f(wire::Protocol::kStackshot);
    for (uint8_t b : req) f.OnHostBytes(wire::ByteView(&b, 1));
    const auto first = f.OnDeviceBytes(wire::ByteView(ack.data(), cut));
    const auto second = f.OnDeviceBytes(wire::ByteView(ack.data() + cut, ack.size() - cut));
    EXPECT_EQ(first.has_value(), cut == ack.size()) << "cut " << cut;
    EXPECT_EQ(second.has_value(), cut < ack.size()) << "cut " << cut;
  }
}

TEST(LineRateFollower, RefusedSwitchKeepsTheBinaryLine) {
  LineRateFollower f(wire::Protocol::kStackshot);
  f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kBusy)).has_value());
  // The request was answered: a later acknowledgement belongs to another one.
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
  EXPECT_EQ(f.dialect(), wire::Protocol::kStackshot);
}

TEST(LineRateFollower, AnotherModeOrNoRequestSwitchesNothing) {
  LineRateFollower f(wire::Protocol::kStackshot);
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
  f.OnHostBytes(ModeWrite(GlobalMode::kAdvanced));
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
  // The latest write decides.
  f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
  f.OnHostBytes(ModeWrite(GlobalMode::kAdvanced));
  EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
}

TEST(LineRateFollower, FixedLineProtocolsNeverChange) {
  for (wire::Protocol p : {wire::Protocol::kDmc, wire::Protocol::kDfmoco}) {
    LineRateFollower f(p);
    f.OnHostBytes(ModeWrite(GlobalMode::kMotionDfMoco));
    EXPECT_FALSE(f.OnDeviceBytes(ModeAnswer(Action::kRspOk)).has_value());
    EXPECT_EQ(f.dialect(), p);
  }
}

TEST(TapDeviceSpec, SerialTcpAndBarePathsAreTakenAndOthersNamed) {
  auto s = ParseDeviceSpec("serial:/dev/ttyUSB0");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_FALSE(std::get<DeviceSpec>(s).tcp);
  EXPECT_EQ(std::get<DeviceSpec>(s).path, "/dev/ttyUSB0");
  s = ParseDeviceSpec("/dev/ttyACM0");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_EQ(std::get<DeviceSpec>(s).path, "/dev/ttyACM0");
  s = ParseDeviceSpec("tcp:192.168.1.20:5000");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_TRUE(std::get<DeviceSpec>(s).tcp);
  EXPECT_EQ(std::get<DeviceSpec>(s).host, "192.168.1.20");
  EXPECT_EQ(std::get<DeviceSpec>(s).port, 5000);
  s = ParseDeviceSpec("tcp:[::1]:7");
  ASSERT_TRUE(std::holds_alternative<DeviceSpec>(s));
  EXPECT_EQ(std::get<DeviceSpec>(s).host, "::1");
  for (const char* bad :
       {"", "serial:", "tcp:5000", "tcp:host:0", "tcp:host:70000", "tcp:host:12x", "udp:host:5"}) {
    const auto r = ParseDeviceSpec(bad);
    ASSERT_TRUE(std::holds_alternative<std::string>(r)) << bad;
    EXPECT_NE(std::get<std::string>(r).find("serial:PATH"), std::string::npos) << bad;
  }
}

TEST(TapDeviceSpec, DefaultModelPerProtocolIsTheEmulatedOne) {
  EXPECT_EQ(DefaultTapDevice(wire::Protocol::kDmc), "dmc16");
  EXPECT_EQ(DefaultTapDevice(wire::Protocol::kDfmoco), "dfmoco");
  EXPECT_EQ(DefaultTapDevice(wire::Protocol::kStackshot), "stackshot3x");
}

// emulator/serve/tap_cli_test.sh sends these bytes to switch a StackShot.
TEST(LineRateFollower, DfmocoModeWriteIsTheOneTheCommandLineTestSends) {
  EXPECT_EQ(wire::ToHex(ModeWrite(GlobalMode::kMotionDfMoco)), "55109e01010848");
}

// The recording is written off the forwarding path in batches; a tap stopped
// right after the last chunk crossed (well inside a batch's window) still
// records every chunk, in order, both ways.
TEST(TapRecording, StopRightAfterTheLastChunkRecordsEveryChunkInOrder) {
  namespace asio = transport::asio;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tap_test." + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  // An echo device on a PTY, on its own io thread.
  asio::io_context device_io;
  sim::Scheduler device_scheduler;
  transport::RealtimeDriver device_driver(device_io, device_scheduler);
  transport::ServeOptions opts;
  opts.no_pacing = true;
  opts.log = [](std::string_view) {};
  transport::DeviceServer device_server(device_driver, "pty:" + (dir / "device").string(), opts);
  transport::testing::EchoDevice echo(device_server.sink());
  device_server.Serve(echo);
  echo.PowerOn();
  device_driver.Start();
  std::thread device_thread([&] { device_io.run(); });
  // The tap in front of it, on its own.
  asio::io_context tap_io;
  sim::Scheduler tap_scheduler;
  transport::RealtimeDriver tap_driver(tap_io, tap_scheduler);
  TapConfig config;
  config.protocol = wire::Protocol::kDmc;
  config.device = "serial:" + (dir / "device").string();
  config.host = "pty:" + (dir / "host").string();
  config.record_path = (dir / "tapped.jsonl").string();
  Tap tap(tap_driver, config, [](std::string_view) {});
  tap.Start();
  tap_driver.Start();
  std::thread tap_thread([&] { tap_io.run(); });

  const int fd = transport::testing::OpenPtyHost((dir / "host").string());
  ASSERT_GE(fd, 0);
  wire::Bytes sent;
  wire::Bytes back;
  for (int i = 0; i < 50; ++i) {
    const wire::Bytes chunk(static_cast<size_t>(1 + i % 7), static_cast<uint8_t>(i));
    ASSERT_TRUE(transport::testing::WriteAll(fd, chunk.data(), chunk.size()));
    sent.insert(sent.end(), chunk.begin(), chunk.end());
    while (back.size() < sent.size()) {
      pollfd p{fd, POLLIN, 0};
      ASSERT_GT(poll(&p, 1, 5000), 0) << "no echo";
      uint8_t buf[256];
      const ssize_t n = read(fd, buf, sizeof buf);
      ASSERT_GT(n, 0);
      back.insert(back.end(), buf, buf + n);
    }
  }
  EXPECT_EQ(back, sent);
  bool stopped = false;
  // As RunTap stops: behind the write completions already queued.
  asio::post(tap_io, [&] {
    asio::post(tap_io, [&] {
      stopped = tap.Stop();
      tap_driver.Stop();
      tap_io.stop();
    });
  });
  tap_thread.join();
  close(fd);
  asio::post(device_io, [&] {
    device_server.Stop();
    device_driver.Stop();
    device_io.stop();
  });
  device_thread.join();
  EXPECT_TRUE(stopped);

  auto loaded = session::LoadSession(dir / "tapped.jsonl");
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const session::Session& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.cut_line, 0u);
  wire::Bytes host_bytes;
  wire::Bytes device_bytes;
  int64_t last_t_ns = 0;
  for (const session::SessionEntry& e : s.entries) {
    EXPECT_GE(e.t_ns, last_t_ns);
    last_t_ns = e.t_ns;
    if (e.is_event) continue;
    wire::Bytes& to = e.from == session::Origin::kHost ? host_bytes : device_bytes;
    to.insert(to.end(), e.bytes.begin(), e.bytes.end());
    // Each echo follows its request: the device never leads the host.
    EXPECT_LE(device_bytes.size(), host_bytes.size());
  }
  EXPECT_EQ(host_bytes, sent);
  EXPECT_EQ(device_bytes, sent);
  std::filesystem::remove_all(dir);
}

// A tap between a host PTY the test opens and a "serial port" that is a PTY
// the test holds the other end of (the device), on its own io thread; the
// flow-control tests (docs/tap.md "Flow control") read either end or not.
class TapBetweenPtys {
 public:
  explicit TapBetweenPtys(const std::string& name, size_t max_queue_bytes) {
    dir_ = std::filesystem::temp_directory_path() /
           ("tap_test." + name + "." + std::to_string(getpid()));
    std::filesystem::create_directories(dir_);
    int slave = -1;
    char slave_name[256] = {};
    EXPECT_EQ(openpty(&device_fd, &slave, slave_name, nullptr, nullptr), 0);
    close(slave);
    TapConfig config;
    config.protocol = wire::Protocol::kDmc;
    config.device = std::string("serial:") + slave_name;
    config.host = "pty:" + (dir_ / "host").string();
    config.record_path = record_path();
    config.max_queue_bytes = max_queue_bytes;
    tap_ = std::make_unique<Tap>(driver_, config, [](std::string_view) {});
    tap_->Start();
    driver_.Start();
    thread_ = std::thread([this] { io_.run(); });
    host_fd = transport::testing::OpenPtyHost((dir_ / "host").string());
    EXPECT_GE(host_fd, 0);
  }
  ~TapBetweenPtys() {
    Stop();
    if (host_fd >= 0) close(host_fd);
    if (device_fd >= 0) close(device_fd);
    std::filesystem::remove_all(dir_);
  }

  // Runs f on the tap's io thread and returns its result.
  template <typename F>
  auto OnTap(F f) {
    std::promise<decltype(f(std::declval<Tap&>()))> result;
    auto future = result.get_future();
    transport::asio::post(io_, [&] { result.set_value(f(*tap_)); });
    return future.get();
  }
  // Polls the tap until cond(tap) or done() (a guard against a hang, not a
  // measure of time). Returns cond's last value.
  bool WaitFor(const std::function<bool(Tap&)>& cond, const std::function<bool()>& done) {
    for (int i = 0; i < 20000; ++i) {
      if (OnTap(cond)) return true;
      if (done()) return OnTap(cond);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    return OnTap(cond);
  }
  bool Stop() {
    if (!thread_.joinable()) return stopped_;
    // As RunTap stops: behind the write completions already queued.
    transport::asio::post(io_, [this] {
      transport::asio::post(io_, [this] {
        stopped_ = tap_->Stop();
        stats_ = tap_->stats();
        driver_.Stop();
        io_.stop();
      });
    });
    thread_.join();
    return stopped_;
  }
  const TapStats& final_stats() const { return stats_; }
  std::string record_path() const { return (dir_ / "tapped.jsonl").string(); }

  int host_fd = -1;
  int device_fd = -1;

 private:
  std::filesystem::path dir_;
  transport::asio::io_context io_;
  sim::Scheduler scheduler_;
  transport::RealtimeDriver driver_{io_, scheduler_};
  std::unique_ptr<Tap> tap_;
  std::thread thread_;
  bool stopped_ = false;
  TapStats stats_;
};

wire::Bytes Pattern(size_t n) {
  wire::Bytes b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>((i * 7 + i / 251) & 0xff);
  return b;
}

// Reads from fd until `want` bytes came; a read that stalls fails (a guard
// against a hang, generous for a loaded machine).
wire::Bytes ReadExactly(int fd, size_t want) {
  wire::Bytes got;
  got.reserve(want);
  uint8_t buf[65536];
  while (got.size() < want) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 10000) <= 0) break;
    const ssize_t n = read(fd, buf, std::min(sizeof buf, want - got.size()));
    if (n <= 0) break;
    got.insert(got.end(), buf, buf + n);
  }
  return got;
}

struct Recorded {
  wire::Bytes host;
  wire::Bytes device;
  std::vector<nlohmann::json> lost;  // "lost" events
};
Recorded LoadRecorded(const std::string& path) {
  Recorded r;
  auto loaded = session::LoadSession(path);
  EXPECT_TRUE(std::holds_alternative<session::Session>(loaded));
  if (!std::holds_alternative<session::Session>(loaded)) return r;
  for (const session::SessionEntry& e : std::get<session::Session>(loaded).entries) {
    if (e.is_event) {
      if (e.event.value("event", "") == "lost") r.lost.push_back(e.event);
      continue;
    }
    wire::Bytes& to = e.from == session::Origin::kHost ? r.host : r.device;
    to.insert(to.end(), e.bytes.begin(), e.bytes.end());
  }
  return r;
}

// A device sending 1,000,000 bytes to a host that has opened the port but
// not read yet: the tap stops reading the device once the host's queue is
// full (the device's writes wait), and when the host reads, every byte
// arrives, in order, and is recorded once. Nothing is lost or dropped.
TEST(TapFlowControl, DeviceFloodToAHostNotReadingIsDeliveredWholeAndRecorded) {
  constexpr size_t kSent = 1'000'000;
  constexpr size_t kMaxQueue = 256 * 1024;
  TapBetweenPtys t("device_flood", kMaxQueue);
  ASSERT_GE(t.host_fd, 0);
  const wire::Bytes sent = Pattern(kSent);
  std::atomic<bool> written{false};
  std::thread device([&] {
    EXPECT_TRUE(transport::testing::WriteAll(t.device_fd, sent.data(), sent.size()));
    written = true;
  });
  // The host reads nothing until the tap holds the device back (or, as it
  // did before flow control, the device got rid of everything).
  EXPECT_TRUE(t.WaitFor([](Tap& tap) { return tap.device_held(); }, [&] { return written.load(); }))
      << "the tap never held the device back";
  EXPECT_LE(t.OnTap([](Tap& tap) { return tap.stats().peak_to_host_bytes; }), kMaxQueue);
  const wire::Bytes got = ReadExactly(t.host_fd, kSent);
  device.join();
  EXPECT_EQ(got.size(), kSent);
  EXPECT_TRUE(got == sent) << "the host got other bytes than the device sent";
  // The tap learns that its last write completed a moment after the host
  // has read it: a write still in flight at the stop counts as lost.
  EXPECT_TRUE(
      t.WaitFor([](Tap& tap) { return tap.stats().device_bytes == kSent; }, [] { return false; }));
  ASSERT_TRUE(t.Stop());
  const TapStats& s = t.final_stats();
  EXPECT_EQ(s.device_read_bytes, kSent);
  EXPECT_EQ(s.device_bytes, kSent);
  EXPECT_EQ(s.lost_to_host_bytes, 0u);
  EXPECT_LE(s.peak_to_host_bytes, kMaxQueue);
  const Recorded r = LoadRecorded(t.record_path());
  EXPECT_EQ(r.device.size(), kSent);
  EXPECT_TRUE(r.device == sent) << "the recording differs from what was delivered";
  EXPECT_TRUE(r.lost.empty());
}

// A host writing 4 MiB far ahead of a device that does not read: the tap
// holds at most max_queue_bytes (plus one read) for the device and stops
// reading the host; when the device reads, every byte arrives and is
// recorded once.
TEST(TapFlowControl, HostFarAheadOfADeviceNotReadingKeepsMemoryBounded) {
  constexpr size_t kSent = 4 << 20;
  constexpr size_t kMaxQueue = 64 * 1024;
  constexpr size_t kOneRead = 4096;
  TapBetweenPtys t("host_ahead", kMaxQueue);
  ASSERT_GE(t.host_fd, 0);
  const wire::Bytes sent = Pattern(kSent);
  std::atomic<bool> written{false};
  std::thread host([&] {
    EXPECT_TRUE(transport::testing::WriteAll(t.host_fd, sent.data(), sent.size()));
    written = true;
  });
  EXPECT_TRUE(t.WaitFor([](Tap& tap) { return tap.host_held(); }, [&] { return written.load(); }))
      << "the tap never held the host back";
  EXPECT_LE(t.OnTap([](Tap& tap) { return tap.to_device_queued(); }), kMaxQueue + kOneRead);
  EXPECT_LE(t.OnTap([](Tap& tap) { return tap.stats().peak_to_device_bytes; }),
            kMaxQueue + kOneRead);
  const wire::Bytes got = ReadExactly(t.device_fd, kSent);
  host.join();
  EXPECT_EQ(got.size(), kSent);
  EXPECT_TRUE(got == sent) << "the device got other bytes than the host sent";
  EXPECT_TRUE(
      t.WaitFor([](Tap& tap) { return tap.stats().host_bytes == kSent; }, [] { return false; }));
  ASSERT_TRUE(t.Stop());
  const TapStats& s = t.final_stats();
  EXPECT_EQ(s.host_bytes, kSent);
  EXPECT_EQ(s.dropped_bytes, 0u);
  EXPECT_LE(s.peak_to_device_bytes, kMaxQueue + kOneRead);
  const Recorded r = LoadRecorded(t.record_path());
  EXPECT_EQ(r.host.size(), kSent);
  EXPECT_TRUE(r.host == sent) << "the recording differs from what was delivered";
  EXPECT_TRUE(r.lost.empty());
}

// Bytes the tap took in but could not deliver are never recorded as
// traffic but as "lost" events with their count: device output still queued
// for a host that has not read it when the tap stops.
TEST(TapFlowControl, OutputQueuedForAHostAtStopIsALostEventNotTraffic) {
  constexpr size_t kMaxQueue = 256 * 1024;
  TapBetweenPtys t("lost_to_host", kMaxQueue);
  ASSERT_GE(t.host_fd, 0);
  // More than the host's PTY holds, less than the tap's queue.
  const wire::Bytes said = Pattern(200 * 1000);
  std::thread device(
      [&] { EXPECT_TRUE(transport::testing::WriteAll(t.device_fd, said.data(), said.size())); });
  EXPECT_TRUE(t.WaitFor(
      [&](Tap& tap) { return tap.device_held() || tap.stats().device_read_bytes == said.size(); },
      [] { return false; }));
  device.join();
  ASSERT_TRUE(t.Stop());
  const TapStats& s = t.final_stats();
  EXPECT_EQ(s.device_read_bytes, said.size());
  EXPECT_EQ(s.device_bytes + s.lost_to_host_bytes, said.size());
  EXPECT_GT(s.lost_to_host_bytes, 0u);
  const Recorded r = LoadRecorded(t.record_path());
  EXPECT_EQ(r.device.size(), s.device_bytes);
  ASSERT_EQ(r.lost.size(), 1u);
  EXPECT_EQ(r.lost[0].value("to", ""), "host");
  EXPECT_EQ(r.lost[0].value("bytes", uint64_t{0}), s.lost_to_host_bytes);
}

// A device that goes away with host bytes queued for it: those bytes, and
// the host's bytes while it is away, are lost events, never traffic.
TEST(TapFlowControl, HostBytesQueuedForADeviceThatWentAwayAreLostEvents) {
  constexpr size_t kMaxQueue = 64 * 1024;
  TapBetweenPtys t("lost_to_device", kMaxQueue);
  ASSERT_GE(t.host_fd, 0);
  const wire::Bytes sent = Pattern(400 * 1000);
  std::thread host(
      [&] { EXPECT_TRUE(transport::testing::WriteAll(t.host_fd, sent.data(), sent.size())); });
  EXPECT_TRUE(t.WaitFor([](Tap& tap) { return tap.host_held(); }, [] { return false; }));
  close(t.device_fd);  // the device goes away
  t.device_fd = -1;
  host.join();  // the host is read again: its bytes are dropped until the device is back
  EXPECT_TRUE(t.WaitFor(
      [&](Tap& tap) { return tap.stats().host_bytes + tap.stats().dropped_bytes == sent.size(); },
      [] { return false; }));
  ASSERT_TRUE(t.Stop());
  const TapStats& s = t.final_stats();
  EXPECT_EQ(s.device_losses, 1u);
  EXPECT_EQ(s.host_bytes + s.dropped_bytes, sent.size());
  EXPECT_GT(s.dropped_bytes, 0u);
  const Recorded r = LoadRecorded(t.record_path());
  EXPECT_EQ(r.host.size(), s.host_bytes);
  EXPECT_TRUE(std::equal(r.host.begin(), r.host.end(), sent.begin()));
  uint64_t lost = 0;
  for (const nlohmann::json& e : r.lost) {
    EXPECT_EQ(e.value("to", ""), "device");
    lost += e.value("bytes", uint64_t{0});
  }
  EXPECT_EQ(lost, s.dropped_bytes);
}

}  // namespace
}  // namespace moco::serve
