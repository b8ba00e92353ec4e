// Tests for the Link session (link.h) over an in-memory stream: the tap's
// view and timestamps, the outgoing queue's cap and hold policy, reclaim
// order, link cuts and power cycles, faults applied on the link.
#include "transport/link.h"

#include <gtest/gtest.h>

#include "transport/test_support.h"
#include "transport/usb_bridge_pacer.h"
#include "wire/protocol.h"

namespace moco::transport {
namespace {

using sim::kNsPerMs;
using testing::EchoDevice;
using testing::RunUntil;

// The far end of an in-memory stream, driven by the test.
struct FakeEnd {
  asio::io_context* io = nullptr;
  std::string written;
  std::vector<size_t> write_sizes;  // one entry per AsyncWriteAll
  // The link's clock when each write began: the driver's NowNs(), which the
  // link's writer decides by (the scheduler's Now() may lag behind it).
  std::vector<sim::TimeNs> write_times;
  RealtimeDriver* clock = nullptr;
  ByteStream::Handler pending_read;
  asio::mutable_buffer read_buf;
  bool closed = false;
  wire::Bytes to_reclaim;
  size_t available = 0;  // what the kernel would count as unread

  void HostSends(std::string_view s) {
    ASSERT_TRUE(pending_read) << "the link is not reading";
    ASSERT_LE(s.size(), read_buf.size());
    std::memcpy(read_buf.data(), s.data(), s.size());
    asio::post(*io, [h = std::move(pending_read), n = s.size()] { h(ErrorCode(), n); });
    pending_read = nullptr;
  }
  void HostHangsUp() {
    ASSERT_TRUE(pending_read);
    asio::post(*io, [h = std::move(pending_read)] { h(asio::error::eof, 0); });
    pending_read = nullptr;
  }
};

class FakeStream final : public ByteStream {
 public:
  explicit FakeStream(std::shared_ptr<FakeEnd> end) : end_(std::move(end)) {}
  void AsyncReadSome(asio::mutable_buffer buffer, Handler handler) override {
    end_->read_buf = buffer;
    end_->pending_read = std::move(handler);
  }
  void AsyncWriteAll(asio::const_buffer buffer, Handler handler) override {
    end_->written.append(static_cast<const char*>(buffer.data()), buffer.size());
    end_->write_sizes.push_back(buffer.size());
    if (end_->clock != nullptr) end_->write_times.push_back(end_->clock->NowNs());
    asio::post(*end_->io, [h = std::move(handler), n = buffer.size()] { h(ErrorCode(), n); });
  }
  void Close() override {
    end_->closed = true;
    if (end_->pending_read) {
      asio::post(*end_->io,
                 [h = std::move(end_->pending_read)] { h(asio::error::operation_aborted, 0); });
      end_->pending_read = nullptr;
    }
  }
  wire::Bytes Reclaim() override { return std::exchange(end_->to_reclaim, {}); }
  std::string PeerName() const override { return "fake"; }
  size_t Available() override { return end_->available; }

 private:
  std::shared_ptr<FakeEnd> end_;
};

struct Recorded {
  sim::TimeNs t_ns;
  std::string what;  // "D:<bytes>" device wrote, "H:<bytes>" host bytes given to the device,
                     // "E:kind detail"
};

class Recorder final : public TrafficObserver {
 public:
  void OnTraffic(sim::TimeNs t, Direction dir, wire::ByteView bytes) override {
    log.push_back({t, std::string(dir == Direction::kToHost ? "D:" : "H:") +
                          std::string(bytes.begin(), bytes.end())});
  }
  void OnLinkEvent(sim::TimeNs t, std::string_view kind, std::string_view detail) override {
    log.push_back({t, "E:" + std::string(kind) + " " + std::string(detail)});
  }
  void OnLineSwitch(sim::TimeNs t, wire::Protocol protocol,
                    const wire::LineSettings& line) override {
    log.push_back(
        {t, "S:" + std::string(wire::ProtocolName(protocol)) + " " + std::to_string(line.baud)});
  }
  std::vector<Recorded> log;
};

class LinkTest : public ::testing::Test {
 protected:
  // The default line: a DMC v2 device's, 115200 8N1 without a bridge.
  void Build(LinkOptions o, const devices::DeviceLine& line = {{.baud = 115200}, {}}) {
    o.observer = &recorder_;
    o.log = [this](std::string_view l) { log_ += std::string(l) + "\n"; };
    link_ = std::make_unique<Link>(driver_, o);
    device_ = std::make_unique<EchoDevice>(*link_);
    device_->SetLine(line);
    device_->PowerOn();
    link_->SetDevice(device_.get());
    driver_.Start();
  }
  std::shared_ptr<FakeEnd> AttachFake() {
    auto end = std::make_shared<FakeEnd>();
    end->io = &io_;
    end->clock = &driver_;
    link_->Attach(std::make_unique<FakeStream>(end));
    return end;
  }
  LinkOptions Unpaced() {
    LinkOptions o;
    o.pacing = false;
    return o;
  }

  asio::io_context io_;
  sim::Scheduler scheduler_;
  RealtimeDriver driver_{io_, scheduler_};
  Recorder recorder_;
  std::unique_ptr<Link> link_;
  std::unique_ptr<EchoDevice> device_;
  std::string log_;
};

TEST_F(LinkTest, TapSeesTheDevicesViewWithNonDecreasingSchedulerTimes) {
  Build(Unpaced());
  auto end = AttachFake();
  end->HostSends("ping");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written == "ping"; }));
  ASSERT_EQ(recorder_.log.size(), 3u);
  EXPECT_EQ(recorder_.log[0].what, "E:host_link open");
  EXPECT_EQ(recorder_.log[1].what, "H:ping");
  EXPECT_EQ(recorder_.log[2].what, "D:ping");
  for (size_t i = 1; i < recorder_.log.size(); ++i) {
    EXPECT_GE(recorder_.log[i].t_ns, recorder_.log[i - 1].t_ns);
  }
  EXPECT_LE(recorder_.log.back().t_ns, scheduler_.Now());
}

// A device timing the line's silence asks whether host bytes still wait:
// those the kernel counts, and after a read that filled the whole buffer,
// those it may not count yet, until the next read.
TEST_F(LinkTest, HostBytesWaitWhileTheKernelHoldsThemOrAReadFilledTheBuffer) {
  Build(Unpaced());
  auto end = AttachFake();
  EXPECT_FALSE(link_->HostBytesWaiting());
  end->available = 7;
  EXPECT_TRUE(link_->HostBytesWaiting());
  end->available = 0;
  const std::string full(4096, 'x');
  end->HostSends(full);
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written.size() == full.size(); }));
  EXPECT_TRUE(link_->HostBytesWaiting()) << "a full read leaves bytes behind";
  ASSERT_TRUE(RunUntil(io_, [&] { return static_cast<bool>(end->pending_read); }));
  end->HostSends("y");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written.size() == full.size() + 1; }));
  EXPECT_FALSE(link_->HostBytesWaiting());
}

TEST_F(LinkTest, PacedHostBytesReachTheDeviceOneCharacterTimeApart) {
  LinkOptions o;  // paced at the echo device's 115200 baud: 11520 bytes/s
  Build(o);
  auto end = AttachFake();
  device_->echo = false;
  end->HostSends("abc");
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->received == "abc"; }));
  // Each byte is handed over at the scheduler time its stop bit ends.
  std::vector<sim::TimeNs> times;
  for (const auto& r : recorder_.log) {
    if (r.what.starts_with("H:")) {
      for (size_t i = 2; i < r.what.size(); ++i) times.push_back(r.t_ns);
    }
  }
  ASSERT_EQ(times.size(), 3u);
  EXPECT_EQ(times[1] - times[0], 173612 - 86806);
  EXPECT_EQ(times[2] - times[1], 260417 - 173612);
}

// The times the device was handed each host byte, in order.
std::vector<sim::TimeNs> HostByteTimes(const std::vector<Recorded>& log) {
  std::vector<sim::TimeNs> times;
  for (const auto& r : log) {
    if (r.what.starts_with("H:")) times.insert(times.end(), r.what.size() - 2, r.t_ns);
  }
  return times;
}

// A device's line changes when it says so (Device::AnnounceLineSwitch): the
// link paces at the announced line from the next byte on and tells its
// observer; it does not poll the device's line between announcements.
TEST_F(LinkTest, PacingFollowsTheLineADeviceAnnouncesFromTheNextByteOn) {
  Build(LinkOptions{});  // 115200 baud: 86806 ns a byte
  auto end = AttachFake();
  device_->echo = false;
  // Changed without an announcement: not followed.
  device_->SetLine({{.baud = 9600}, {}});
  end->HostSends("ab");
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->received == "ab"; }));
  std::vector<sim::TimeNs> t = HostByteTimes(recorder_.log);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(static_cast<double>(t[1] - t[0]), 86806.0, 1.0);

  device_->SwitchLine(wire::Protocol::kDfmoco, {{.baud = 9600}, {}});  // 1041667 ns a byte
  ASSERT_FALSE(recorder_.log.empty());
  EXPECT_EQ(recorder_.log.back().what,
            "S:" + std::string(wire::ProtocolName(wire::Protocol::kDfmoco)) + " 9600");
  end->HostSends("cd");
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->received == "abcd"; }));
  t = HostByteTimes(recorder_.log);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_NEAR(static_cast<double>(t[3] - t[2]), 1041667.0, 1.0);
}

// A device that wraps another (a fault-planting wrapper) announces the inner
// device's switches as its own, so the link follows them too.
TEST_F(LinkTest, AWrappingDeviceRelaysTheInnerDevicesLineSwitches) {
  class Wrapper final : public devices::Device {
   public:
    explicit Wrapper(EchoDevice& inner) : inner_(inner) { RelayLineSwitchesOf(inner_); }
    std::string_view Model() const override { return "wrapper"; }
    devices::DeviceLine Line() const override { return inner_.Line(); }
    void PowerOn() override { inner_.PowerOn(); }
    void PowerOff() override { inner_.PowerOff(); }
    bool Powered() const override { return inner_.Powered(); }
    void OnHostBytes(wire::ByteView bytes) override { inner_.OnHostBytes(bytes); }

   private:
    EchoDevice& inner_;
  };
  Build(LinkOptions{});
  AttachFake();
  EchoDevice inner(*link_);
  inner.PowerOn();
  Wrapper wrapper(inner);
  link_->SetDevice(&wrapper);
  inner.SwitchLine(wire::Protocol::kStackshot, {{.baud = 38400}, {}});
  ASSERT_FALSE(recorder_.log.empty());
  EXPECT_EQ(recorder_.log.back().what,
            "S:" + std::string(wire::ProtocolName(wire::Protocol::kStackshot)) + " 38400");
  link_->SetDevice(device_.get());
}

TEST_F(LinkTest, QueueIsCappedAndOverflowIsCountedAndLogged) {
  LinkOptions o = Unpaced();
  o.max_queue_bytes = 10;
  Build(o);
  link_->SetHostPresent(false);  // nobody reading: output waits
  AttachFake();
  device_->Send("0123456789ABCDEF");
  EXPECT_EQ(link_->queued_bytes(), 10u);
  EXPECT_EQ(link_->stats().overflowed, 6u);
  EXPECT_NE(log_.find("outgoing queue full (10 bytes"), std::string::npos) << log_;
}

TEST_F(LinkTest, HeldOutputFollowsReclaimedBytesInOrder) {
  Build(Unpaced());
  auto end = AttachFake();
  ASSERT_TRUE(link_->host_open());
  device_->Send("AB");
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host == 2; }));
  // The host leaves with "AB" unread in the stream; the stream gives it back.
  end->to_reclaim = {'A', 'B'};
  link_->SetHostPresent(false);
  EXPECT_EQ(link_->stats().reclaimed, 2u);
  device_->Send("CD");
  end->to_reclaim = {};  // a later pass finds nothing more
  link_->SetHostPresent(true);
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written.size() == 6; }));
  EXPECT_EQ(end->written, "ABABCD");  // the far end re-reads AB (it never got it), then CD
  EXPECT_EQ(device_->link_events, (std::vector<bool>{true, false, true}));
}

TEST_F(LinkTest, CutDropsEverythingForItsDurationThenRecovers) {
  Build(Unpaced());
  auto end = AttachFake();
  link_->Cut(30 * kNsPerMs, /*close_stream=*/false);
  EXPECT_TRUE(link_->cut_active());
  end->HostSends("lost");
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_from_host == 4; }));
  EXPECT_EQ(device_->received, "");
  device_->Send("gone");
  EXPECT_EQ(link_->stats().cut_dropped, 8u);
  ASSERT_TRUE(RunUntil(io_, [&] { return !link_->cut_active() && end->pending_read != nullptr; }));
  end->HostSends("back");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written == "back"; }));
  EXPECT_EQ(device_->received, "back");
  bool cut_logged = false;
  for (const auto& r : recorder_.log) cut_logged |= r.what == "E:link_fault cut 30000000";
  EXPECT_TRUE(cut_logged);
}

TEST_F(LinkTest, CutWithCloseDropsTheConnection) {
  Build(Unpaced());
  auto end = AttachFake();
  link_->Cut(kNsPerMs, /*close_stream=*/true);
  EXPECT_TRUE(end->closed);
  EXPECT_FALSE(link_->attached());
  EXPECT_EQ(device_->link_events, (std::vector<bool>{true, false}));
}

TEST_F(LinkTest, PowerCycleTurnsTheDeviceOffThenOnAfterTheDelay) {
  Build(Unpaced());
  AttachFake();
  const sim::TimeNs off_at = driver_.Sync();
  link_->PowerCycle(20 * kNsPerMs);
  EXPECT_FALSE(device_->Powered());
  EXPECT_EQ(device_->power_offs, 1);
  sim::TimeNs on_at = 0;
  ASSERT_TRUE(RunUntil(io_, [&] {
    if (device_->Powered() && on_at == 0) on_at = scheduler_.Now();
    return device_->Powered();
  }));
  EXPECT_EQ(device_->power_ons, 2);
  EXPECT_GE(on_at - off_at, 20 * kNsPerMs);  // scheduler time, not wall time
}

TEST_F(LinkTest, FaultsOnTheLinkAreAppliedPerDirection) {
  LinkOptions o = Unpaced();
  o.faults.to_host.duplicate_rate = 1.0;  // device -> host doubled
  Build(o);
  auto end = AttachFake();
  end->HostSends("xy");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written.size() == 4; }));
  EXPECT_EQ(device_->received, "xy");  // to-device untouched
  EXPECT_EQ(end->written, "xxyy");
  EXPECT_EQ(link_->faults().counts(Direction::kToHost).duplicated, 2u);
}

TEST_F(LinkTest, SetFaultsChangesTheFaultsFromNowOnAndOffAgain) {
  Build(Unpaced());
  auto end = AttachFake();
  device_->Send("a");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written == "a"; }));
  FaultConfig dup;
  dup.to_host.duplicate_rate = 1.0;
  link_->SetFaults(dup);
  EXPECT_TRUE(link_->faults().enabled());
  device_->Send("b");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written == "abb"; }));
  link_->SetFaults(FaultConfig{});
  EXPECT_FALSE(link_->faults().enabled());
  device_->Send("c");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written == "abbc"; }));
  std::vector<std::string> events;
  for (const auto& r : recorder_.log) {
    if (r.what.rfind("E:link_fault", 0) == 0) events.push_back(r.what);
  }
  EXPECT_EQ(events,
            (std::vector<std::string>{"E:link_fault faults on", "E:link_fault faults off"}));
}

TEST_F(LinkTest, HangUpDetachesAndReportsTheReason) {
  Build(Unpaced());
  auto end = std::make_shared<FakeEnd>();
  end->io = &io_;
  std::string reason;
  link_->Attach(std::make_unique<FakeStream>(end), [&](const std::string& r) { reason = r; });
  end->HostHangsUp();
  ASSERT_TRUE(RunUntil(io_, [&] { return !reason.empty(); }));
  EXPECT_EQ(reason, "host closed the connection");
  EXPECT_FALSE(link_->attached());
}

TEST_F(LinkTest, DestroyingTheLinkWithWorkPendingIsSafe) {
  Build(Unpaced());
  auto end = AttachFake();
  device_->Send("pending");
  link_.reset();  // the write completion is still queued in io_
  io_.restart();
  io_.run_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(end->closed);
}

TEST_F(LinkTest, MaxWriteBytesSplitsDeviceOutputIntoWritesNoLargerThanIt) {
  // StackShot Wi-Fi (section 4.2): "The maximum size of a single packet is
  // set to 1000 bytes."
  LinkOptions o = Unpaced();
  o.max_write_bytes = 1000;
  Build(o);
  auto end = AttachFake();
  const std::string out(2500, 'x');
  device_->Send(out);
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written.size() == out.size(); }));
  EXPECT_EQ(end->written, out);
  EXPECT_EQ(end->write_sizes, (std::vector<size_t>{1000, 1000, 500}));
}

TEST_F(LinkTest, WithoutMaxWriteBytesOneWriteCarriesUpTo4096Bytes) {
  Build(Unpaced());
  auto end = AttachFake();
  device_->Send(std::string(2500, 'y'));
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written.size() == 2500; }));
  EXPECT_EQ(end->write_sizes, (std::vector<size_t>{2500}));
}

// Unpaced and fault-free, bytes skip the per-byte queues: the device's view,
// the host's bytes, their order across writes still pending, the counts
// and the queue cap are what the queues would give.
TEST_F(LinkTest, UnpacedFaultFreeBytesPassStraightWithTheQueuesResults) {
  LinkOptions o = Unpaced();
  o.max_queue_bytes = 20;
  Build(o);
  auto end = AttachFake();
  device_->echo = false;
  device_->Send("0123456789ABCDEF");  // one write, still pending during the next ones
  device_->Send("ab");                // queued behind it
  device_->Send("cd");
  device_->Send("ef");  // 20 bytes held (the write counts until done): over the cap
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host == 20; }));
  EXPECT_EQ(end->written, "0123456789ABCDEFabcd");
  EXPECT_EQ(end->write_sizes, (std::vector<size_t>{16, 4}));
  EXPECT_EQ(link_->stats().overflowed, 2u);
  EXPECT_EQ(link_->stats().bytes_from_device, 22u);
  EXPECT_EQ(link_->stats().bytes_to_host, 20u);
  EXPECT_EQ(link_->faults().counts(Direction::kToHost).bytes_in, 22u);
  end->HostSends("hello");
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->received == "hello"; }));
  end->HostSends("!");
  ASSERT_TRUE(RunUntil(io_, [&] { return device_->received == "hello!"; }));
  EXPECT_EQ(link_->stats().bytes_to_device, 6u);
  EXPECT_EQ(link_->faults().counts(Direction::kToDevice).bytes_in, 6u);
  std::vector<std::string> seen;
  for (const auto& r : recorder_.log) seen.push_back(r.what);
  EXPECT_EQ(seen, (std::vector<std::string>{"E:host_link open", "D:0123456789ABCDEF", "D:ab",
                                            "D:cd", "D:ef", "H:hello", "H:!"}));
}

// ---- USB serial bridges (devices/usb_bridge.h) ------------------------------

devices::DeviceLine Bridged(uint32_t baud, const devices::UsbBridge& bridge) {
  return {{.baud = baud}, bridge};
}

// What the bridge makes of the device's writes (LinkTest's recorder: "D:"
// entries with their scheduler times): the UART's arrival time of each byte,
// then the packets, as transport/usb_bridge_pacer.h computes them.
std::vector<UsbBridgePacer::Packet> ExpectedPackets(const std::vector<Recorded>& log,
                                                    const devices::DeviceLine& line) {
  LinePacer uart(line.bridge.uart_paced ? line.serial.BytesPerSecond() : 0);
  std::vector<sim::TimeNs> arrivals;
  for (const Recorded& r : log) {
    if (!r.what.starts_with("D:")) continue;
    for (size_t i = 2; i < r.what.size(); ++i) arrivals.push_back(uart.Take(r.t_ns));
  }
  UsbBridgePacer bridge(line.bridge);
  std::vector<UsbBridgePacer::Packet> packets;
  for (size_t head = 0; head < arrivals.size();) {
    const auto p = bridge.Next(
        arrivals.size() - head, [&](size_t i) { return arrivals[head + i]; }, 0);
    bridge.Sent(p);
    packets.push_back(p);
    head += p.bytes;
  }
  return packets;
}

// The law however late the io thread runs: every write to the host is one or
// more whole packets, in order, and none leaves before its packet is due.
void ExpectWholePacketsNeverEarly(const std::vector<UsbBridgePacer::Packet>& packets,
                                  const FakeEnd& end) {
  ASSERT_EQ(end.write_sizes.size(), end.write_times.size());
  size_t next = 0;
  for (size_t w = 0; w < end.write_sizes.size(); ++w) {
    size_t bytes = 0;
    sim::TimeNs due = 0;
    while (bytes < end.write_sizes[w] && next < packets.size()) {
      bytes += packets[next].bytes;
      due = packets[next].at_ns;
      ++next;
    }
    EXPECT_EQ(bytes, end.write_sizes[w]) << "write " << w << " splits a packet";
    EXPECT_GE(end.write_times[w], due) << "write " << w << " left before its packet was due";
  }
  EXPECT_EQ(next, packets.size());
}

// A StackShot's FTDI chip: a 10-byte reply is clocked out at 38400 baud but
// reaches the host in whole packets at the latency timer's ticks (every
// 16 ms of the device's clock), never byte by byte.
TEST_F(LinkTest, FtdiBridgeDeliversAShortReplyInOnePieceAtTheLatencyTick) {
  const devices::DeviceLine line = Bridged(38400, devices::UsbBridge::Ftdi());
  Build(LinkOptions{}, line);
  auto end = AttachFake();
  device_->echo = false;
  device_->Send("0123456789");
  driver_.Kick();  // the device wrote outside a scheduler callback
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host == 10; }));
  EXPECT_EQ(end->written, "0123456789");
  const auto packets = ExpectedPackets(recorder_.log, line);
  // One packet, unless the reply's 2.6 ms on the UART spans a tick.
  ASSERT_FALSE(packets.empty());
  EXPECT_LE(packets.size(), 2u);
  EXPECT_EQ(packets.back().at_ns % (16 * kNsPerMs), 0);
  ExpectWholePacketsNeverEarly(packets, *end);
  EXPECT_LE(end->write_sizes.size(), packets.size());
  EXPECT_EQ(link_->queued_bytes(), 0u);
}

// A CDC port has no UART: host bytes reach the device at once, and the echo
// leaves in the next 1 ms USB frame; 64-byte packets leave when full.
TEST_F(LinkTest, CdcBridgeIsUnpacedAndDeliversInTheNextUsbFrame) {
  const devices::DeviceLine line = Bridged(115200, devices::UsbBridge::Cdc());
  Build(LinkOptions{}, line);
  auto end = AttachFake();
  end->HostSends("abcdef");
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host == 6; }));
  // Unpaced: the device got all six in one hand-over.
  size_t host_chunks = 0;
  for (const auto& r : recorder_.log) host_chunks += r.what.starts_with("H:") ? 1 : 0;
  EXPECT_EQ(host_chunks, 1u);
  device_->echo = false;
  device_->Send(std::string(200, 'z'));
  driver_.Kick();
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host == 206; }));
  EXPECT_EQ(end->written, "abcdef" + std::string(200, 'z'));
  const auto packets = ExpectedPackets(recorder_.log, line);
  // The echo: one short packet at the next frame. The 200: three full
  // packets at once, the last 8 bytes at the frame after.
  ASSERT_EQ(packets.size(), 5u);
  EXPECT_EQ(packets[0].bytes, 6u);
  EXPECT_EQ(packets[0].at_ns % kNsPerMs, 0);
  for (int i = 1; i <= 3; ++i) {
    EXPECT_EQ(packets[i].bytes, 64u);
    EXPECT_TRUE(packets[i].full);
  }
  EXPECT_EQ(packets[4].bytes, 8u);
  EXPECT_EQ(packets[4].at_ns % kNsPerMs, 0);
  ExpectWholePacketsNeverEarly(packets, *end);
}

// Bytes the bridge holds when the host closes the port are not lost or
// reordered: they go out first when it opens it again.
TEST_F(LinkTest, BytesTheBridgeHoldsWhenTheHostLeavesComeFirstWhenItReturns) {
  Build(LinkOptions{}, Bridged(38400, devices::UsbBridge::Ftdi(255)));
  auto end = AttachFake();
  device_->echo = false;
  const sim::TimeNs sent = driver_.Sync();
  device_->Send("abc");
  driver_.Kick();
  // The UART is done after 0.79 ms; the bridge holds them until its tick,
  // 255 ms after the clock's start: the host leaves and comes back between.
  ASSERT_TRUE(RunUntil(io_, [&] { return driver_.Sync() >= sent + kNsPerMs; }));
  link_->SetHostPresent(false);
  device_->Send("def");
  link_->SetHostPresent(true);
  ASSERT_TRUE(RunUntil(io_, [&] { return link_->stats().bytes_to_host == 6; }));
  EXPECT_EQ(end->written, "abcdef");
  EXPECT_EQ(link_->queued_bytes(), 0u);
}

// --no-pacing turns the bridge off with the UART: bytes pass at once.
TEST_F(LinkTest, WithoutPacingTheBridgeDoesNotHoldBytes) {
  Build(Unpaced(), Bridged(38400, devices::UsbBridge::Ftdi()));
  EXPECT_FALSE(link_->bridge_pacer().active());
  auto end = AttachFake();
  device_->echo = false;
  device_->Send("xyz");
  ASSERT_TRUE(RunUntil(io_, [&] { return end->written == "xyz"; }));
}

}  // namespace
}  // namespace moco::transport
