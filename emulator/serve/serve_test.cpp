// Served DMC-16s end to end over a real PTY and a real TCP socket, the run
// file reader, and start-up errors that name the problem.
#include "serve/serve.h"

#include <poll.h>
#include <sys/stat.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <mutex>
#include <thread>

#include "base/file_io.h"
#include "devices/registry.h"
#include "serve/file_state_store.h"
#include "session/session.h"
#include "transport/dmc_host_client.h"
#include "wire/stackshot.h"
#include "wire/transcript.h"

namespace moco::serve {
namespace {

namespace asio = transport::asio;
namespace testing = transport::testing;
using testing::DmcHostClient;
using transport::DeviceServer;
namespace fs = std::filesystem;

fs::path TempDir() {
  const fs::path d =
      fs::temp_directory_path() / ("moco_serve_test_" + std::to_string(getpid()) + "_" +
                                   ::testing::UnitTest::GetInstance()->current_test_info()->name());
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Talks DMC v2 to served device `i`: HI, a move with its position updates, status.
void Exercise(Emulator& e, size_t i) {
  DeviceServer& s = e.server(i);
  const int fd =
      s.pty() != nullptr ? testing::OpenPtyHost(s.pty_path()) : testing::ConnectTcp(s.tcp_port());
  ASSERT_GE(fd, 0);
  DmcHostClient c(fd);
  ASSERT_TRUE(c.Send(0x10001, dmc::HiRequest{}));
  auto hi = c.ReplyTo(0x10001, 5000);
  ASSERT_TRUE(hi.has_value());
  ASSERT_TRUE(std::holds_alternative<dmc::HiResponse>(hi->msg));
  EXPECT_EQ(std::get<dmc::HiResponse>(hi->msg).NameText(), "DMC-16");
  ASSERT_TRUE(c.Send(0x10002, dmc::MotorMove{2, 300}));
  auto mv = c.ReplyTo(0x10002, 5000);
  ASSERT_TRUE(mv.has_value());
  EXPECT_EQ(std::get<dmc::MotorMoveResponse>(mv->msg).moving, 1);
  // Position updates arrive until the motor stops on 300.
  bool arrived = false;
  for (int n = 0; n < 100 && !arrived; ++n) {
    auto f = c.Next(5000);
    ASSERT_TRUE(f.has_value());
    if (const auto* p = std::get_if<dmc::MotorPositionReport>(&f->msg)) {
      arrived = p->positions_steps.at(1) == 300;
    }
  }
  EXPECT_TRUE(arrived);
  ASSERT_TRUE(c.Send(0x10003, dmc::MotorStatusRequest{}));
  auto st = c.ReplyTo(0x10003, 5000);
  ASSERT_TRUE(st.has_value());
  EXPECT_EQ(std::get<dmc::MotorStatusResponse>(st->msg).moving_bits, 0u);
  EXPECT_EQ(c.bad_frames(), 0u);
  close(fd);
}

TEST(Serve, Dmc16EndToEndOverPtyAndTcpWithRecording) {
  const fs::path dir = TempDir();
  EmulatorConfig config;
  config.log_level = LogLevel::kError;
  DeviceConfig pty;
  pty.endpoint = "pty:" + (dir / "dmc16").string();
  pty.record_path = (dir / "pty.jsonl").string();
  DeviceConfig tcp;
  tcp.endpoint = "tcp:127.0.0.1:0";
  config.devices = {pty, tcp};
  {
    Emulator e(config, [](std::string_view) {});
    EXPECT_EQ(e.name(0), "dmc16");
    EXPECT_EQ(e.name(1), "dmc16-2");
    e.Start();
    std::thread io([&] { e.Run(); });
    Exercise(e, 0);
    Exercise(e, 1);
    asio::post(e.io(), [&] { e.Stop(); });
    io.join();
    EXPECT_FALSE(fs::exists(dir / "dmc16")) << "the symlink is removed on stop";
  }
  auto loaded = session::LoadSession(dir / "pty.jsonl");
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const session::Session& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.header.protocol, wire::Protocol::kDmc);
  bool saw_move = false;
  for (const auto& entry : s.entries) {
    for (const auto& d : entry.decoded)
      saw_move = saw_move || d.find("MOTOR_MOVE motor=2") != std::string::npos;
  }
  EXPECT_TRUE(saw_move) << "recorded traffic carries decoded lines";
  fs::remove_all(dir);
}

TEST(Serve, DeviceEventsAndControlActionsAreLoggedAndRecorded) {
  const fs::path dir = TempDir();
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  EmulatorConfig config;
  config.log_level = LogLevel::kWarn;
  DeviceConfig dev;
  dev.profile_path = std::string(root ? root : ".") + "/fixtures/profiles/dmc16-boom.json";
  dev.endpoint = "tcp:127.0.0.1:0";
  dev.record_path = (dir / "boom.jsonl").string();
  config.devices = {dev};
  std::vector<std::string> log;
  std::mutex log_mutex;
  {
    Emulator e(config, [&](std::string_view l) {
      std::lock_guard lock(log_mutex);
      log.emplace_back(l);
    });
    control::ControlChannel channel(e.scheduler());
    channel.AddDevice(e.name(0), e.device(0), &e.link_control(0));
    e.AttachControl(channel);
    e.Start();
    std::thread io([&] { e.Run(); });
    const int fd = testing::ConnectTcp(e.server(0).tcp_port());
    ASSERT_GE(fd, 0);
    DmcHostClient c(fd);
    // Boom (motor 3, 888.9 steps per degree) down into the floor at 30 deg/s.
    ASSERT_TRUE(c.Send(1, dmc::MotorSetSpeed{3, 26667, 266670}));
    ASSERT_TRUE(c.ReplyTo(1, 5000).has_value());
    ASSERT_TRUE(c.Send(2, dmc::MotorMove{3, -59 * 889}));
    ASSERT_TRUE(c.ReplyTo(2, 5000).has_value());
    bool hard_stop = false;
    for (int n = 0; n < 200 && !hard_stop; ++n) {
      auto f = c.Next(5000);
      ASSERT_TRUE(f.has_value()) << "no MOTOR_HARD_STOP from the collision";
      hard_stop = std::holds_alternative<dmc::MotorHardStop>(f->msg);
    }
    // An action from the control channel, on the scheduler's thread.
    std::promise<std::string> reply;
    asio::post(e.io(), [&] {
      e.driver().Sync();
      reply.set_value(channel.Handle(R"({"cmd":"estop","engaged":true})"));
      e.driver().Kick();
    });
    EXPECT_NE(reply.get_future().get().find("\"ok\":true"), std::string::npos);
    close(fd);
    asio::post(e.io(), [&] { e.Stop(); });
    io.join();
  }
  bool logged = false;
  for (const std::string& l : log) logged = logged || l.find("\"collision\"") != std::string::npos;
  EXPECT_TRUE(logged) << "device events are logged at warn";

  auto loaded = session::LoadSession(dir / "boom.jsonl");
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const session::Session& s = std::get<session::Session>(loaded);
  const session::SessionEntry* collision = nullptr;
  const session::SessionEntry* estop = nullptr;
  for (const auto& entry : s.entries) {
    if (!entry.is_event) continue;
    if (entry.event.value("event", "") == "collision" && collision == nullptr) collision = &entry;
    if (entry.event.value("event", "") == "estop") estop = &entry;
  }
  ASSERT_NE(collision, nullptr) << "the collision is in the recording";
  EXPECT_EQ(collision->event["source"], "device");
  EXPECT_EQ(collision->event["with"], "floor");
  EXPECT_EQ(collision->event["halted_motors"], true);
  EXPECT_EQ(collision->event["seq"].get<uint64_t>() >= 1, true);
  ASSERT_NE(estop, nullptr) << "the control action is in the recording";
  EXPECT_EQ(estop->event["source"], "control");
  EXPECT_GT(estop->t_ns, collision->t_ns);
  fs::remove_all(dir);
}

// Reads lines ("\r\n"-terminated) from fd until one starts with `prefix`.
std::string ReadLineStartingWith(int fd, const std::string& prefix, std::string& buffer) {
  for (int guard = 0; guard < 1000; ++guard) {
    size_t eol;
    while ((eol = buffer.find("\r\n")) != std::string::npos) {
      std::string line = buffer.substr(0, eol);
      buffer.erase(0, eol + 2);
      if (line.rfind(prefix, 0) == 0) return line;
    }
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 5000) <= 0) return "";
    char tmp[256];
    const ssize_t r = read(fd, tmp, sizeof tmp);
    if (r <= 0) return "";
    buffer.append(tmp, static_cast<size_t>(r));
  }
  return "";
}

TEST(Serve, DfmocoEndToEndOverPtyAtTheSketchLineRate) {
  const fs::path dir = TempDir();
  EmulatorConfig config;
  config.log_level = LogLevel::kError;
  DeviceConfig d;
  d.model = "dfmoco";
  d.endpoint = "pty:" + (dir / "dfmoco").string();
  config.devices = {d};
  Emulator e(config, [](std::string_view) {});
  e.Start();
  std::thread io([&] { e.Run(); });
  const int fd = testing::OpenPtyHost(e.server(0).pty_path());
  ASSERT_GE(fd, 0);
  std::string buf;
  EXPECT_EQ(ReadLineStartingWith(fd, "hi", buf), "hi 2 4 2.0.0") << "boot hello, held for the host";
  const std::string cmds = "ms\r\nmm 1 100\r\n";
  ASSERT_TRUE(testing::WriteAll(fd, reinterpret_cast<const uint8_t*>(cmds.data()), cmds.size()));
  EXPECT_EQ(ReadLineStartingWith(fd, "ms", buf), "ms 0000");
  EXPECT_EQ(ReadLineStartingWith(fd, "mm", buf), "mm 1 100");
  EXPECT_EQ(ReadLineStartingWith(fd, "mp 1 100", buf), "mp 1 100") << "the report after the stop";
  close(fd);
  asio::post(e.io(), [&] { e.Stop(); });
  io.join();
  fs::remove_all(dir);
}

// Sends one StackShot command and returns the reply packet (nullopt on timeout).
std::optional<stackshot::Packet> StackshotAsk(int fd, const stackshot::HostCommand& c) {
  wire::Bytes out;
  if (!stackshot::EncodeHostCommand(c, out, stackshot::ChecksumAlgorithm::kConstant69)) return {};
  if (!testing::WriteAll(fd, out.data(), out.size())) return {};
  stackshot::PacketDecoder decoder(/*from_device=*/true);
  std::vector<stackshot::DecodedPacket> got;
  for (int i = 0; i < 100 && got.empty(); ++i) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, 5000) <= 0) return {};
    uint8_t buf[256];
    const ssize_t r = read(fd, buf, sizeof buf);
    if (r <= 0) return {};
    decoder.Feed(wire::ByteView(buf, static_cast<size_t>(r)), got);
  }
  if (got.empty()) return {};
  return got.front().packet;
}

TEST(Serve, Stackshot3xEndToEndOverPtyKeepsItsSerialNumberInTheStateFile) {
  const fs::path dir = TempDir();
  EmulatorConfig config;
  config.log_level = LogLevel::kError;
  DeviceConfig d;
  d.model = "stackshot3x";
  d.endpoint = "pty:" + (dir / "ss").string();
  d.state_path = (dir / "nvm.json").string();
  config.devices = {d};
  auto serial_write = stackshot::HostCommand{stackshot::Id(stackshot::Command::kSerialNumber),
                                             stackshot::Action::kWrite,
                                             0,
                                             false,
                                             false,
                                             stackshot::U32Value{4242}};
  for (int run = 0; run < 2; ++run) {
    Emulator e(config, [](std::string_view) {});
    EXPECT_EQ(e.state_path(0), d.state_path);
    e.Start();
    std::thread io([&] { e.Run(); });
    const int fd = testing::OpenPtyHost(e.server(0).pty_path());
    ASSERT_GE(fd, 0);
    auto ping =
        StackshotAsk(fd, {stackshot::Id(stackshot::Command::kPing), stackshot::Action::kRead, 0,
                          false, false, stackshot::PingRequest{0x5A}});
    ASSERT_TRUE(ping.has_value());
    EXPECT_EQ(ping->data, (wire::Bytes{0xA5, 0x00})) << "PING answers the value xor 0xFF";
    // Write-once serial number: the first run writes it, the second (a new
    // process on the same state file) finds it taken.
    auto w = StackshotAsk(fd, serial_write);
    ASSERT_TRUE(w.has_value());
    EXPECT_EQ(w->action, static_cast<uint8_t>(run == 0 ? stackshot::Action::kRspOk
                                                       : stackshot::Action::kFailed))
        << "run " << run;
    close(fd);
    asio::post(e.io(), [&] { e.Stop(); });
    io.join();
    EXPECT_TRUE(fs::exists(dir / "nvm.json"));
  }
  fs::remove_all(dir);
}

// A StackShot 3X set to DfMoco mode on its panel powers on speaking DFMoco
// (stackshot-protocol.txt section 3): its recording says so with a
// "line_switch" event, and a transcript that follows the recorded switches
// (as `mocosim decode` does) reads the DFMoco lines after it.
TEST(Serve, Stackshot3xPoweringOnInDfmocoModeIsRecordedAsALineSwitch) {
  const fs::path dir = TempDir();
  {
    FileStateStore nvm(dir / "nvm.json");
    devices::StateLoad first;
    ASSERT_FALSE(nvm.Open(&first).has_value());
    sim::Scheduler sched;
    struct Null final : devices::ByteSink {
      void Write(wire::ByteView) override {}
    } sink;
    devices::CreateDevice("stackshot3x", "", sched, sink, &nvm,
                          devices::DeviceStart{wire::Protocol::kStackshotDfmoco});
  }
  EmulatorConfig config;
  config.log_level = LogLevel::kError;
  DeviceConfig d;
  d.model = "stackshot3x";
  d.endpoint = "pty:" + (dir / "ss").string();
  d.state_path = (dir / "nvm.json").string();
  d.record_path = (dir / "ss.jsonl").string();
  config.devices = {d};
  {
    Emulator e(config, [](std::string_view) {});
    e.Start();
    std::thread io([&] { e.Run(); });
    const int fd = testing::OpenPtyHost(e.server(0).pty_path());
    ASSERT_GE(fd, 0);
    ASSERT_EQ(write(fd, "hi\r\n", 4), 4);
    std::string answer;
    for (int i = 0; i < 50 && answer.find('\n') == std::string::npos; ++i) {
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 100) <= 0) continue;
      char buf[64];
      const ssize_t n = read(fd, buf, sizeof buf);
      if (n > 0) answer.append(buf, static_cast<size_t>(n));
    }
    EXPECT_EQ(answer.rfind("hi ", 0), 0u) << answer;
    close(fd);
    asio::post(e.io(), [&] { e.Stop(); });
    io.join();
  }
  auto loaded = session::LoadSession(dir / "ss.jsonl");
  ASSERT_TRUE(std::holds_alternative<session::Session>(loaded));
  const session::Session& s = std::get<session::Session>(loaded);
  EXPECT_EQ(s.header.protocol, wire::Protocol::kStackshot);
  wire::TranscriptDecoder decoder(s.header.protocol);
  std::string text;
  size_t problems = 0;
  bool switched = false;
  auto add = [&](const std::vector<wire::TranscriptLine>& lines) {
    for (const wire::TranscriptLine& l : lines) {
      text += l.text + "\n";
      problems += l.problem;
    }
  };
  for (const session::SessionEntry& entry : s.entries) {
    if (const auto p = session::LineSwitchOf(entry)) {
      EXPECT_EQ(*p, wire::Protocol::kStackshotDfmoco);
      EXPECT_EQ(entry.event.value("baud", 0u), 57600u);
      switched = true;
      decoder.SwitchTo(*p);
    }
    if (entry.is_event) continue;
    EXPECT_TRUE(switched) << "the switch comes before the first byte";
    add(decoder.Feed(entry.from == session::Origin::kHost ? wire::Side::kHost : wire::Side::kDevice,
                     entry.bytes));
  }
  add(decoder.Finish());
  EXPECT_TRUE(switched);
  EXPECT_EQ(problems, 0u) << text;
  EXPECT_NE(text.find("hello: protocol 1, 3 motors"), std::string::npos) << text;
  fs::remove_all(dir);
}

// The host side of StackShot Wi-Fi discovery: a TCP server, then FINDSTACK
// datagrams to the controller until it connects (stackshot-protocol.txt 4.1).
int AcceptAfterFindstack(int listener, uint16_t udp_port) {
  const int udp = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(udp_port);
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  int fd = -1;
  for (int attempt = 0; attempt < 50 && fd < 0; ++attempt) {
    sendto(udp, "FINDSTACK", 9, 0, reinterpret_cast<sockaddr*>(&to), sizeof to);
    pollfd p{listener, POLLIN, 0};
    if (poll(&p, 1, 100) > 0) fd = accept(listener, nullptr, nullptr);
  }
  close(udp);
  return fd;
}

TEST(Serve, Stackshot3xWifiAnswersFindstackConnectsAndReconnects) {
  const fs::path dir = TempDir();
  const int listener = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(listener, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  ASSERT_EQ(listen(listener, 4), 0);
  socklen_t len = sizeof a;
  getsockname(listener, reinterpret_cast<sockaddr*>(&a), &len);
  const uint16_t host_port = ntohs(a.sin_port);

  EmulatorConfig config;
  config.log_level = LogLevel::kError;
  DeviceConfig d;
  d.model = "stackshot3x";
  d.endpoint = "wifi:127.0.0.1:0:" + std::to_string(host_port);
  d.state_path = (dir / "nvm.json").string();
  config.devices = {d};
  Emulator e(config, [](std::string_view) {});
  ASSERT_NE(e.server(0).wifi(), nullptr);
  const uint16_t udp_port = e.server(0).wifi()->udp_port();
  e.Start();
  std::thread io([&] { e.Run(); });
  for (int round = 0; round < 2; ++round) {
    // The second round: the host went away; the controller waits for the
    // broadcast again and reconnects.
    const int fd = AcceptAfterFindstack(listener, udp_port);
    ASSERT_GE(fd, 0) << "round " << round;
    auto ping =
        StackshotAsk(fd, {stackshot::Id(stackshot::Command::kPing), stackshot::Action::kRead, 0,
                          false, false, stackshot::PingRequest{0x0F}});
    ASSERT_TRUE(ping.has_value()) << "round " << round;
    EXPECT_EQ(ping->data, (wire::Bytes{0xF0, 0x00}));
    close(fd);
  }
  asio::post(e.io(), [&] { e.Stop(); });
  io.join();
  close(listener);
  fs::remove_all(dir);
}

TEST(Serve, TcpLogLinesNameTheBoundPortNotPortZero) {
  std::mutex mu;
  std::vector<std::string> lines;
  EmulatorConfig config;
  DeviceConfig d;
  d.endpoint = "tcp:127.0.0.1:0";
  config.devices = {d};
  Emulator e(config, [&](std::string_view l) {
    std::lock_guard<std::mutex> lock(mu);
    lines.emplace_back(l);
  });
  const std::string bound = "tcp 127.0.0.1:" + std::to_string(e.server(0).tcp_port());
  e.Start();
  std::thread io([&] { e.Run(); });
  Exercise(e, 0);  // a host connects and disconnects: the link logs both
  asio::post(e.io(), [&] { e.Stop(); });
  io.join();
  bool connected = false;
  for (const std::string& l : lines) {
    EXPECT_EQ(l.find("127.0.0.1:0"), std::string::npos) << l;
    connected = connected || (l.find(bound + ": host connected") != std::string::npos);
  }
  EXPECT_TRUE(connected) << "no \"" << bound << ": host connected\" line";
}

TEST(Serve, ARecordingsHeaderNamesTheBoundPortNotPortZero) {
  const fs::path dir = TempDir();
  EmulatorConfig config;
  config.log_level = LogLevel::kError;
  DeviceConfig d;
  d.endpoint = "tcp:127.0.0.1:0";
  d.record_path = (dir / "rec.jsonl").string();
  config.devices = {d};
  uint16_t port = 0;
  {
    Emulator e(config, [](std::string_view) {});
    port = e.server(0).tcp_port();
    e.Start();
    asio::post(e.io(), [&] { e.Stop(); });
    e.Run();
  }
  std::ifstream in(dir / "rec.jsonl");
  std::string header;
  std::getline(in, header);
  EXPECT_NE(header.find("127.0.0.1:" + std::to_string(port)), std::string::npos) << header;
  EXPECT_EQ(header.find("127.0.0.1:0\""), std::string::npos) << header;
  fs::remove_all(dir);
}

TEST(Serve, WifiWithoutAnAddressListensOnLoopbackAndSaysSo) {
  const fs::path dir = TempDir();
  std::vector<std::string> lines;
  EmulatorConfig config;
  DeviceConfig d;
  d.model = "stackshot3x";
  d.endpoint = "wifi::0";  // the default address, any free UDP port
  d.state_path = (dir / "nvm.json").string();
  config.devices = {d};
  Emulator e(config, [&](std::string_view l) { lines.emplace_back(l); });
  EXPECT_NE(e.server(0).Where().find("udp 127.0.0.1:"), std::string::npos) << e.server(0).Where();
  e.Start();
  bool logged = false;
  for (const std::string& l : lines)
    logged = logged || l.find("udp 127.0.0.1:") != std::string::npos;
  EXPECT_TRUE(logged) << "the start-up line names the address listened on";
  e.Stop();
  fs::remove_all(dir);
}

TEST(Serve, TakenTcpPortIsAClearErrorAndLeavesNothingOpen) {
  const fs::path dir = TempDir();
  EmulatorConfig first;
  DeviceConfig d;
  d.endpoint = "tcp:127.0.0.1:0";
  first.devices = {d};
  Emulator a(first, [](std::string_view) {});
  EmulatorConfig second;
  DeviceConfig p;
  p.endpoint = "pty:" + (dir / "x").string();
  DeviceConfig t;
  t.endpoint = "tcp:127.0.0.1:" + std::to_string(a.server(0).tcp_port());
  second.devices = {p, t};
  try {
    Emulator b(second, [](std::string_view) {});
    FAIL() << "a taken port must be refused";
  } catch (const std::exception& ex) {
    EXPECT_NE(std::string(ex.what()).find("dmc16-2"), std::string::npos) << ex.what();
  }
  EXPECT_FALSE(fs::exists(dir / "x")) << "the PTY opened first was closed again";
  fs::remove_all(dir);
}

TEST(Serve, BadProfileNamesTheField) {
  const fs::path dir = TempDir();
  std::ofstream(dir / "p.json") << R"({"motor_count": 99})";
  EmulatorConfig c;
  DeviceConfig d;
  d.endpoint = "tcp:127.0.0.1:0";
  d.profile_path = (dir / "p.json").string();
  c.devices = {d};
  try {
    Emulator e(c, [](std::string_view) {});
    FAIL();
  } catch (const std::exception& ex) {
    EXPECT_NE(std::string(ex.what()).find("\"motor_count\" is 99"), std::string::npos) << ex.what();
  }
  fs::remove_all(dir);
}

TEST(RunConfig, ParsesDevicesAndResolvesRelativePaths) {
  const nlohmann::json j = nlohmann::json::parse(R"({
    "control": "ctl.sock", "log_level": "warn",
    "devices": [{"model": "dmc16", "endpoint": "pty:dev/a", "record": "a.jsonl"},
                {"endpoint": "tcp:5000", "name": "b", "no_pacing": true, "faults": "drop=0.1"}]})");
  const EmulatorConfig c = ParseRunConfig(j, "run file r.json", "/base");
  ASSERT_EQ(c.devices.size(), 2u);
  EXPECT_EQ(c.control_path, "/base/ctl.sock");
  EXPECT_EQ(c.log_level, LogLevel::kWarn);
  EXPECT_EQ(c.devices[0].endpoint, "pty:/base/dev/a");
  EXPECT_EQ(c.devices[0].record_path, "/base/a.jsonl");
  EXPECT_EQ(c.devices[1].name, "b");
  EXPECT_TRUE(c.devices[1].no_pacing);
}

// The error ParseRunConfig gives for the run file `text` ("" if it takes it).
std::string RunConfigErrorOf(const char* text) {
  try {
    ParseRunConfig(nlohmann::json::parse(text), "run file r.json", "/b");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(RunConfig, ErrorsNameTheField) {
  const auto error_of = RunConfigErrorOf;
  EXPECT_NE(error_of(R"({})").find("\"devices\" is missing"), std::string::npos);
  EXPECT_NE(error_of(R"({"devices": [{"model": "dmc99", "endpoint": "tcp:1"}]})")
                .find("devices[0].model"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"devices": [{"model": "dmc16"}]})").find("devices[0].endpoint"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"devices": [{"endpoint": "tcp:1", "recrod": "x"}]})")
                .find("\"devices[0].recrod\" is not a known field"),
            std::string::npos);
  EXPECT_NE(
      error_of(R"({"log_level": "loud", "devices": [{"endpoint": "tcp:1"}]})").find("log_level"),
      std::string::npos);
}

// --- the files a served device writes (docs/files.md) ---------------------------------------

std::string RefusalOf(const EmulatorConfig& c, std::vector<std::string>* log = nullptr) {
  try {
    Emulator e(c, [log](std::string_view l) {
      if (log != nullptr) log->emplace_back(l);
    });
  } catch (const std::exception& ex) {
    return ex.what();
  }
  return "";
}

DeviceConfig TcpDevice(std::string model = "dmc16", std::string name = "") {
  DeviceConfig d;
  d.model = std::move(model);
  d.name = std::move(name);
  d.endpoint = "tcp:127.0.0.1:0";
  return d;
}

TEST(ServeFiles, TwoDevicesRecordingToOneFileAreRefusedAtStart) {
  const fs::path dir = TempDir();
  EmulatorConfig c;
  DeviceConfig a = TcpDevice("dmc16", "a"), b = TcpDevice("dmc16", "b");
  a.record_path = (dir / "rec.jsonl").string();
  b.record_path = (dir / "." / "rec.jsonl").string();
  c.devices = {a, b};
  const std::string error = RefusalOf(c);
  EXPECT_NE(error.find("b's --record " + b.record_path + " is also a's --record"),
            std::string::npos)
      << error;
  EXPECT_FALSE(fs::exists(dir / "rec.jsonl"));
  fs::remove_all(dir);
}

TEST(ServeFiles, ARecordingOntoTheProfileIsRefusedAndTheProfileKept) {
  const fs::path dir = TempDir();
  const fs::path profile = dir / "p.json";
  { std::ofstream(profile) << "{}"; }
  fs::create_symlink(profile, dir / "link.json");
  EmulatorConfig c;
  DeviceConfig d = TcpDevice();
  d.profile_path = profile.string();
  d.record_path = (dir / "link.json").string();
  c.devices = {d};
  const std::string error = RefusalOf(c);
  EXPECT_NE(error.find("--record " + d.record_path + " is also --profile"), std::string::npos)
      << error;
  std::ifstream in(profile);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "{}");
  fs::remove_all(dir);
}

TEST(ServeFiles, ARecordingIntoADirectoryIsRefusedAtStartNamingIt) {
  const fs::path dir = TempDir();
  EmulatorConfig c;
  DeviceConfig d = TcpDevice();
  d.record_path = dir.string();
  c.devices = {d};
  const std::string error = RefusalOf(c);
  EXPECT_NE(error.find(dir.string() + ": is a directory"), std::string::npos) << error;
  EXPECT_TRUE(fs::is_directory(dir));
  EXPECT_FALSE(fs::exists(dir.string() + ".corrupt"));
  fs::remove_all(dir);
}

TEST(ServeFiles, ARecordingIntoAFifoIsWrittenInPlaceAndTheFifoStaysAFifo) {
  const fs::path dir = TempDir();
  const fs::path fifo = dir / "rec.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] {
    std::ifstream in(fifo, std::ios::binary);
    received.assign(std::istreambuf_iterator<char>(in), {});
  });
  {
    EmulatorConfig c;
    c.log_level = LogLevel::kError;
    DeviceConfig d = TcpDevice();
    d.record_path = fifo.string();
    c.devices = {d};
    Emulator e(c, [](std::string_view) {});
    e.Start();
    asio::post(e.io(), [&] { e.Stop(); });
    EXPECT_EQ(e.Run(), 0);
  }
  reader.join();
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  EXPECT_NE(received.find("\"mocosim_session\""), std::string::npos) << received;
  fs::remove_all(dir);
}

TEST(ServeFiles, ReplacingAnExistingRecordingIsLogged) {
  const fs::path dir = TempDir();
  { std::ofstream(dir / "rec.jsonl") << "old\n"; }
  EmulatorConfig c;
  DeviceConfig d = TcpDevice();
  d.record_path = (dir / "rec.jsonl").string();
  c.devices = {d};
  std::vector<std::string> log;
  {
    Emulator e(c, [&log](std::string_view l) { log.emplace_back(l); });
  }
  bool said = false;
  for (const std::string& l : log)
    said |= l.find("rec.jsonl exists; the recording replaces it") != std::string::npos;
  EXPECT_TRUE(said);
  fs::remove_all(dir);
}

TEST(ServeFiles, AStartThatFailsLeavesAnEarlierRecordingAsItWas) {
  const fs::path dir = TempDir();
  { std::ofstream(dir / "rec.jsonl") << "old\n"; }
  EmulatorConfig c;
  DeviceConfig a = TcpDevice("dmc16", "a");
  a.record_path = (dir / "rec.jsonl").string();
  DeviceConfig b = TcpDevice("dmc16", "b");
  b.faults = "nonsense=1";
  c.devices = {a, b};
  EXPECT_NE(RefusalOf(c), "");
  std::ifstream in(dir / "rec.jsonl");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "old\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  fs::remove_all(dir);
}

TEST(ServeFiles, ASecondEmulatorOnTheSameStateFileIsRefusedNamingTheFileAndTheFix) {
  const fs::path dir = TempDir();
  EmulatorConfig c;
  DeviceConfig d = TcpDevice("stackshot3x");
  d.state_path = (dir / "nvm.json").string();
  c.devices = {d};
  Emulator first(c, [](std::string_view) {});
  const std::string error = RefusalOf(c);
  EXPECT_NE(error.find(d.state_path), std::string::npos) << error;
  EXPECT_NE(error.find("--state PATH"), std::string::npos) << error;
  fs::remove_all(dir);
}

TEST(ServeFiles, ACorruptStateFileIsWarnedOnTheConsoleAndKept) {
  const fs::path dir = TempDir();
  { std::ofstream(dir / "nvm.json") << R"({"serial_number": )"; }
  EmulatorConfig c;
  c.log_level = LogLevel::kWarn;
  DeviceConfig d = TcpDevice("stackshot3x");
  d.state_path = (dir / "nvm.json").string();
  c.devices = {d};
  std::vector<std::string> log;
  {
    Emulator e(c, [&log](std::string_view l) { log.emplace_back(l); });
  }
  bool warned = false;
  for (const std::string& l : log) {
    warned |= l.find(d.state_path + " is not valid JSON") != std::string::npos &&
              l.find("nvm.json.corrupt") != std::string::npos;
  }
  EXPECT_TRUE(warned);
  EXPECT_TRUE(fs::exists(dir / "nvm.json.corrupt"));
  fs::remove_all(dir);
}

TEST(ServeFiles, AStateFileForAModelWithoutNvmIsRefused) {
  EmulatorConfig c;
  DeviceConfig d = TcpDevice("dmc16");
  d.state_path = "/tmp/never-written.json";
  c.devices = {d};
  EXPECT_NE(RefusalOf(c).find("keeps no state"), std::string::npos);
  const nlohmann::json j = nlohmann::json::parse(
      R"({"devices": [{"model": "dmc16", "endpoint": "tcp:1", "state": "s.json"}]})");
  try {
    ParseRunConfig(j, "run file r.json", "/b");
    ADD_FAILURE() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("devices[0].state"), std::string::npos) << e.what();
  }
}

TEST(ServeFiles, RunFilesAreReadBoundedAndDevicesRefused) {
  const fs::path dir = TempDir();
  for (const std::string& p : {std::string("/dev/zero"), dir.string()}) {
    try {
      LoadRunConfig(p);
      ADD_FAILURE() << p;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("run file " + p), std::string::npos) << e.what();
    }
  }
  { std::ofstream(dir / "big.json") << std::string(base::kMaxInputFileBytes + 1, ' '); }
  try {
    LoadRunConfig((dir / "big.json").string());
    ADD_FAILURE() << "a 4 MiB run file was read";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("4 MiB"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(RunConfig, ErrorsSpeakOfTheRunFileAndItsDocumentNotAProfile) {
  const auto error_of = RunConfigErrorOf;
  for (const char* text : {R"({"devices": [{"endpoint": "tcp:1"}], "devics": 1})",
                           R"({"devices": [{"endpoint": "tcp:1", "x": 1}]})", R"([1])"}) {
    const std::string e = error_of(text);
    EXPECT_NE(e.find("run file r.json"), std::string::npos) << e;
    EXPECT_EQ(e.find("profile"), std::string::npos) << e;
    if (text[0] == '{') {
      EXPECT_NE(e.find("docs/run-files.md"), std::string::npos) << e;
    }
  }
}

}  // namespace
}  // namespace moco::serve
