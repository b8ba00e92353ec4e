// `mocosim tap`: a recording proxy between a host and a real device (see tap.h).
#include "serve/tap.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdio>
#include <deque>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "base/file_io.h"
#include "devices/registry.h"

namespace moco::serve {

namespace asio = transport::asio;
using transport::ErrorCode;

// The host side's device: what the host writes goes on to the real device.
class Tap::Forwarder final : public devices::Device {
 public:
  explicit Forwarder(Tap& tap) : tap_(tap) {}
  std::string_view Model() const override { return tap_.config_.device_model; }
  devices::DeviceLine Line() const override { return {{.baud = tap_.baud_}, {}}; }
  void PowerOn() override {}
  void PowerOff() override {}
  bool Powered() const override { return true; }
  void OnHostBytes(wire::ByteView bytes) override { tap_.ToDevice(bytes); }

 private:
  Tap& tap_;
};

// Records the tap's traffic and events off the forwarding path. Traffic is
// what was delivered: device bytes as the host link wrote them to the host
// (OnDelivered), host bytes as the tap wrote them to the device (Traffic);
// the link's OnTraffic (what was taken in) is not recorded. The io thread
// only appends each chunk (its time, its side, its bytes) to a batch
// in memory and goes back to forwarding; a writer thread takes the batch,
// decodes the messages each chunk completed in the dialect then on the line,
// and writes the batch's lines with one write. A batch is written
// kBatchWindow after its first chunk, or at once past kBatchBytes, and
// Finish() writes what is left: a stopped tap's recording is complete.
class Tap::Recorder final : public transport::TrafficObserver {
 public:
  static constexpr std::chrono::milliseconds kBatchWindow{50};
  static constexpr size_t kBatchBytes = 64 * 1024;

  explicit Recorder(wire::Protocol protocol) : dialect_(protocol) {}
  ~Recorder() { Finish(nullptr); }

  // Records into `writer` from now on (the header names the host side, known
  // once it is open; nothing crosses before Tap::Start()). The writer must
  // outlive Finish(); until then only the writer thread touches it.
  void Start(session::SessionWriter* writer) {
    writer_ = writer;
    decoder_ = std::make_unique<wire::TranscriptDecoder>(dialect_);
    recording_ = true;
    thread_ = std::thread([this] { Run(); });
  }

  void OnTraffic(sim::TimeNs, transport::Direction, wire::ByteView) override {}
  void OnDelivered(sim::TimeNs t_ns, transport::Direction dir, wire::ByteView bytes) override {
    if (dir != transport::Direction::kToHost) return;
    // A dialect change takes effect after the device byte that made it.
    while (!switches_.empty() && passed_to_host_ + bytes.size() >= switches_.front().first) {
      const size_t part = static_cast<size_t>(switches_.front().first - passed_to_host_);
      if (part > 0) Traffic(t_ns, /*host=*/false, bytes.first(part));
      delivered_to_host_ += part;
      passed_to_host_ += part;
      bytes = bytes.subspan(part);
      SetDialect(switches_.front().second);
      switches_.pop_front();
    }
    delivered_to_host_ += bytes.size();
    passed_to_host_ += bytes.size();
    if (!bytes.empty()) Traffic(t_ns, /*host=*/false, bytes);
  }
  // Device bytes that will never be delivered, in order with the delivered
  // ones: dialect changes after them take effect.
  void SkipToHost(uint64_t n) {
    passed_to_host_ += n;
    while (!switches_.empty() && passed_to_host_ >= switches_.front().first) {
      SetDialect(switches_.front().second);
      switches_.pop_front();
    }
  }
  // Chunks are decoded in `dialect` once the first `device_bytes` device
  // bytes are delivered (or skipped): the device's own switch is recorded
  // where the host got it.
  void SetDialectAfter(uint64_t device_bytes, wire::Protocol dialect) {
    if (passed_to_host_ >= device_bytes) {
      SetDialect(dialect);
      return;
    }
    switches_.emplace_back(device_bytes, dialect);
  }
  // A chunk delivered: host -> device when `host`, else device -> host.
  void Traffic(sim::TimeNs t_ns, bool host, wire::ByteView bytes) {
    if (!recording_) return;
    Item item;
    item.kind = Kind::kTraffic;
    item.t_ns = t_ns;
    item.host = host;
    Push(std::move(item), bytes);
  }
  uint64_t delivered_to_host() const { return delivered_to_host_; }
  void OnLinkEvent(sim::TimeNs t_ns, std::string_view kind, std::string_view detail) override {
    Event({{"t_ns", t_ns}, {"event", std::string(kind)}, {"detail", std::string(detail)}});
  }
  // An event line with its "t_ns".
  void Event(nlohmann::json line) {
    if (!recording_) return;
    Item item;
    item.kind = Kind::kEvent;
    item.event = std::move(line);
    Push(std::move(item), {});
  }
  // Chunks from now on are decoded in `dialect`, after a "line_switch"
  // event (docs/sessions.md) at the time of the last line recorded.
  void SetDialect(wire::Protocol dialect) {
    if (!recording_) {
      dialect_ = dialect;
      return;
    }
    Item item;
    item.kind = Kind::kDialect;
    item.dialect = dialect;
    Push(std::move(item), {});
  }

  // Writes what is pending and stops the writer thread; the caller then
  // finishes the writer. Returns false with a message when a batch could not
  // be recorded. Idempotent.
  bool Finish(std::string* error) {
    recording_ = false;
    if (thread_.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mu_);
        stop_ = true;
      }
      cv_.notify_one();
      thread_.join();
    }
    if (failure_.empty()) return true;
    if (error != nullptr) *error = failure_;
    return false;
  }

 private:
  enum class Kind : uint8_t { kTraffic, kEvent, kDialect };
  struct Item {
    Kind kind = Kind::kTraffic;
    bool host = false;                              // kTraffic: host -> device
    wire::Protocol dialect = wire::Protocol::kDmc;  // kDialect
    sim::TimeNs t_ns = 0;                           // kTraffic, kDialect
    size_t size = 0;                                // kTraffic: its bytes in Batch::bytes
    nlohmann::json event;                           // kEvent
  };
  struct Batch {
    std::vector<Item> items;
    wire::Bytes bytes;  // the traffic items' bytes, end to end
  };

  // io thread. Wakes the writer only for a batch's first item (and once when
  // it grows past kBatchBytes): a chunk costs a copy, not a system call.
  void Push(Item item, wire::ByteView bytes) {
    bool wake = false;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stop_) return;
      // Times never go back: a switch is stamped with the last line's time.
      if (item.kind == Kind::kEvent) {
        last_t_ = std::max(last_t_, item.event.value("t_ns", sim::TimeNs{0}));
      } else {
        item.t_ns = std::max(item.t_ns, last_t_);
        last_t_ = item.t_ns;
      }
      const size_t before = pending_.bytes.size();
      wake = pending_.items.empty();
      item.size = bytes.size();
      pending_.bytes.insert(pending_.bytes.end(), bytes.begin(), bytes.end());
      pending_.items.push_back(std::move(item));
      wake = wake || (before < kBatchBytes && pending_.bytes.size() >= kBatchBytes);
    }
    if (wake) cv_.notify_one();
  }

  // The writer thread.
  void Run() {
    Batch work;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mu_);
        cv_.wait(lock, [this] { return stop_ || !pending_.items.empty(); });
        // Lets the batch fill: a burst of chunks is one write.
        cv_.wait_for(lock, kBatchWindow,
                     [this] { return stop_ || pending_.bytes.size() >= kBatchBytes; });
        std::swap(work, pending_);
        if (work.items.empty() && stop_) return;
      }
      try {
        Write(work);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mu_);
        failure_ = std::string("recording a batch of traffic failed: ") + e.what();
        stop_ = true;  // later chunks are not recorded
        return;
      }
      work.items.clear();
      work.bytes.clear();
    }
  }

  void Write(Batch& batch) {
    lines_.clear();
    size_t offset = 0;
    for (Item& item : batch.items) {
      switch (item.kind) {
        case Kind::kDialect:
          lines_.push_back(session::LineSwitchEvent(item.t_ns, item.dialect,
                                                    wire::Info(item.dialect).line,
                                                    "acknowledged by the device"));
          decoder_->SwitchTo(item.dialect);
          break;
        case Kind::kEvent:
          lines_.push_back(session::SessionEntry::Event(std::move(item.event)));
          break;
        case Kind::kTraffic: {
          const wire::ByteView bytes(batch.bytes.data() + offset, item.size);
          offset += item.size;
          session::SessionEntry e;
          e.t_ns = item.t_ns;
          e.from = item.host ? session::Origin::kHost : session::Origin::kDevice;
          e.bytes.assign(bytes.begin(), bytes.end());
          for (const wire::TranscriptLine& l :
               decoder_->Feed(item.host ? wire::Side::kHost : wire::Side::kDevice, bytes)) {
            e.decoded.push_back(l.text);
          }
          lines_.push_back(std::move(e));
          break;
        }
      }
    }
    writer_->Append(lines_);
  }

  bool recording_ = false;                                    // io thread
  uint64_t delivered_to_host_ = 0;                            // io thread
  uint64_t passed_to_host_ = 0;                               // io thread: delivered or skipped
  std::deque<std::pair<uint64_t, wire::Protocol>> switches_;  // io thread
  std::mutex mu_;
  std::condition_variable cv_;
  Batch pending_;           // guarded by mu_
  sim::TimeNs last_t_ = 0;  // guarded by mu_: the time of the last item pushed
  bool stop_ = false;       // guarded by mu_
  std::string failure_;     // guarded by mu_; read after the join
  std::thread thread_;
  // The writer thread's (before Start() and after the join: the caller's).
  session::SessionWriter* writer_ = nullptr;
  wire::Protocol dialect_;
  std::unique_ptr<wire::TranscriptDecoder> decoder_;
  std::vector<session::SessionEntry> lines_;
};

std::variant<DeviceSpec, std::string> ParseDeviceSpec(std::string_view spec) {
  const std::string forms =
      "give the device side as serial:PATH (e.g. serial:/dev/ttyUSB0) or tcp:HOST:PORT (e.g. "
      "tcp:192.168.1.20:5000)";
  DeviceSpec d;
  if (spec.starts_with("tcp:")) {
    const std::string_view rest = spec.substr(4);
    const size_t colon = rest.rfind(':');
    if (colon == std::string_view::npos || colon == 0 || colon + 1 == rest.size()) {
      return "device \"" + std::string(spec) + "\" has no HOST:PORT; " + forms;
    }
    std::string host(rest.substr(0, colon));
    if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
      host = host.substr(1, host.size() - 2);
    }
    const std::string port_text(rest.substr(colon + 1));
    unsigned long port = 0;
    try {
      size_t used = 0;
      port = std::stoul(port_text, &used);
      if (used != port_text.size()) port = 0;
    } catch (const std::exception&) {
      port = 0;
    }
    if (port == 0 || port > 65535) {
      return "device \"" + std::string(spec) + "\": port \"" + port_text + "\" is not 1..65535; " +
             forms;
    }
    d.tcp = true;
    d.host = host;
    d.port = static_cast<uint16_t>(port);
    return d;
  }
  std::string_view path = spec;
  if (path.starts_with("serial:")) path.remove_prefix(7);
  if (path.starts_with("pty:")) path.remove_prefix(4);
  if (path.empty()) return "the device side is empty; " + forms;
  if (path.find(':') != std::string_view::npos && !path.starts_with("/") &&
      !path.starts_with(".")) {
    return "device \"" + std::string(spec) + "\" is neither serial:PATH nor tcp:HOST:PORT; " +
           forms;
  }
  d.path = std::string(path);
  return d;
}

std::string DefaultTapDevice(wire::Protocol protocol) {
  for (const devices::DeviceModel& m : devices::DeviceModels()) {
    if (m.protocol == protocol) return std::string(m.name);
  }
  // A protocol a model's line switches to (a StackShot's DfMoco mode).
  for (const devices::DeviceModel& m : devices::DeviceModels()) {
    for (const wire::Protocol p : m.also_speaks) {
      if (p == protocol) return std::string(m.name);
    }
  }
  return {};
}

Tap::Tap(transport::RealtimeDriver& driver, TapConfig config, transport::LogFn log)
    : driver_(driver),
      config_(std::move(config)),
      log_(log ? std::move(log) : transport::LogToStderr),
      follower_(config_.protocol) {
  auto parsed = ParseDeviceSpec(config_.device);
  if (const auto* e = std::get_if<std::string>(&parsed)) throw std::runtime_error(*e);
  spec_ = std::get<DeviceSpec>(parsed);
  if (config_.device_model.empty()) config_.device_model = DefaultTapDevice(config_.protocol);
  baud_ = config_.baud != 0 ? config_.baud : wire::Info(config_.protocol).line.baud;
  if (!spec_.tcp && !transport::IsStandardBaud(baud_)) {
    throw std::runtime_error("--baud " + std::to_string(baud_) +
                             " is not a standard rate; use e.g. one of the protocols' lines: " +
                             wire::DefaultBaudList());
  }
  // The paths the tap writes (the recording, the host's PTY link) against
  // each other and what it reads, by any spelling (base::SamePath): a
  // recording into its own PTY blocks the tap and is lost at the stop.
  const std::string host_pty = config_.host.starts_with("pty:") ? config_.host.substr(4) : "";
  const std::string device_path = spec_.tcp ? "" : spec_.path;
  auto refuse = [](const std::string& what, const std::string& path, const std::string& other,
                   const std::string& other_path, const std::string& why, const std::string& fix) {
    throw std::runtime_error(what + " " + path + " is also " + other + " " + other_path + ": " +
                             why + "; " + fix);
  };
  if (!host_pty.empty() && base::SamePath(host_pty, device_path)) {
    refuse("--pty", host_pty, "--device", device_path,
           "the host's PTY link would replace the device's port",
           "give --pty a path of its own (e.g. /tmp/tap-host)");
  }
  if (!config_.record_path.empty()) {
    if (auto error = base::CheckOutputPath(config_.record_path, "")) {
      throw std::runtime_error("the recording " + *error);
    }
    const std::string& rec = config_.record_path;
    if (base::SamePath(rec, device_path)) {
      refuse("--record", rec, "--device", device_path,
             "the recording would be written into the device's port",
             "give --record a file of its own (e.g. session.jsonl)");
    }
    if (base::SamePath(rec, host_pty)) {
      refuse("--record", rec, "--pty", host_pty,
             "the recording would be written into the tap's own PTY (blocking it) and lost "
             "when it stops",
             "give --record a file of its own (e.g. session.jsonl)");
    }
    if (base::SamePath(rec, config_.profile)) {
      refuse("--record", rec, "--profile", config_.profile,
             "writing the recording would destroy the profile", "give --record another path");
    }
  }
  // The device first: a host never finds a port with nothing behind it.
  OpenDevice();
  forwarder_ = std::make_unique<Forwarder>(*this);
  recorder_ = std::make_unique<Recorder>(config_.protocol);
  transport::ServeOptions opts;
  opts.no_pacing = true;  // the real line paces; the tap adds nothing
  opts.observer = recorder_.get();
  opts.max_queue_bytes = config_.max_queue_bytes;
  opts.on_drain = [this] { OnDrain(); };
  opts.log = [this](std::string_view line) { log_("host side: " + std::string(line)); };
  server_ = std::make_unique<transport::DeviceServer>(driver_, config_.host, opts);
  if (server_->spec().kind == transport::EndpointSpec::Kind::kWifi) {
    throw std::runtime_error("the host side is a PTY (pty:PATH) or a TCP port (tcp:[HOST:]PORT)");
  }
  // Last, so that a tap that cannot start leaves no recording behind.
  if (!config_.record_path.empty()) {
    session::SessionHeader h;
    h.protocol = config_.protocol;
    h.device = config_.device_model;
    h.clock = "real";
    h.note = !config_.note.empty() ? config_.note
                                   : "tapped by mocosim tap between host " + server_->Where() +
                                         " and device " + config_.device;
    h.tolerance_time_ms = config_.time_tolerance_ms;
    if (!config_.profile.empty()) h.extra["profile"] = config_.profile;
    h.extra["tap"] = {{"host", server_->Where()}, {"device", config_.device}, {"baud", baud_}};
    writer_ = std::make_unique<session::SessionWriter>(config_.record_path, h);
  }
}

Tap::~Tap() {
  Stop(nullptr);
  alive_.reset();
}

void Tap::OpenDevice() {
  asio::io_context& io = driver_.io();
  if (spec_.tcp) {
    device_stream_ = transport::ConnectTcpStream(io, spec_.host, spec_.port);
    serial_ = nullptr;
  } else {
    auto serial =
        transport::SerialStream::Open(io, spec_.path, {.baud = baud_, .rtscts = config_.rtscts});
    serial_ = serial.get();
    device_stream_ = std::move(serial);
  }
  ++device_gen_;
  writing_ = false;
  device_reading_ = false;
  device_held_ = false;
}

void Tap::Start() {
  if (started_ || stopped_) return;
  started_ = true;
  if (writer_) recorder_->Start(writer_.get());
  server_->Serve(*forwarder_);
  ReadDevice();
  if (transport::PtyPort* pty = server_->pty()) {
    // The host's port reads back the device's speed until the host sets its own.
    pty->SetLineBaud(baud_);
    host_line_seen_ = pty->LineBaud();
    poll_timer_ = driver_.scheduler().After(config_.poll_ns, [this] { PollHostLine(); });
  }
  driver_.Kick();
}

void Tap::ReadDevice() {
  if (device_stream_ == nullptr || stopped_ || device_reading_) return;
  // Flow control: a read only when the host's queue has room for all of it,
  // so the link never drops device output; until then the device's bytes
  // wait in the kernel and the line (OnDrain reads on).
  const transport::Link& link = server_->link();
  if (link.queued_bytes() + read_buf_.size() > config_.max_queue_bytes) {
    device_held_ = true;
    return;
  }
  device_held_ = false;
  device_reading_ = true;
  device_stream_->AsyncReadSome(
      asio::buffer(read_buf_),
      [this, weak = std::weak_ptr<bool>(alive_), gen = device_gen_](const ErrorCode& ec, size_t n) {
        if (weak.expired() || gen != device_gen_) return;
        device_reading_ = false;
        if (stopped_) return;
        OnDeviceRead(ec, n);
      });
}

void Tap::OnDrain() {
  if (!started_ || stopped_) return;
  NoteLinkLosses();
  FlushLosses();
  if (device_held_) ReadDevice();
}

void Tap::NoteLinkLosses() {
  // The link drops device output only where no host can take it: a TCP host
  // not connected, or leaving with bytes queued (a full queue is never
  // reached: ReadDevice waits for room).
  const transport::LinkStats& ls = server_->link().stats();
  const uint64_t lost = ls.overflowed + ls.discarded + ls.cut_dropped;
  if (lost <= link_lost_seen_) return;
  stats_.lost_to_host_bytes += lost - link_lost_seen_;
  recorder_->SkipToHost(lost - link_lost_seen_);
  lost_to_host_unrecorded_ += lost - link_lost_seen_;
  link_lost_seen_ = lost;
}

void Tap::FlushLosses() {
  if (lost_to_host_unrecorded_ > 0) {
    Event({{"event", "lost"},
           {"to", "host"},
           {"bytes", lost_to_host_unrecorded_},
           {"detail", "device output no host was connected to take"}});
    lost_to_host_unrecorded_ = 0;
  }
  if (lost_to_device_unrecorded_ > 0) {
    Event({{"event", "lost"},
           {"to", "device"},
           {"bytes", lost_to_device_unrecorded_},
           {"detail", "host bytes while the device was away"}});
    lost_to_device_unrecorded_ = 0;
  }
}

TapStats Tap::stats() const {
  TapStats s = stats_;
  s.device_bytes = recorder_ ? recorder_->delivered_to_host() : 0;
  return s;
}

void Tap::OnDeviceRead(const ErrorCode& ec, size_t n) {
  if (ec) {
    DeviceLost(ec == asio::error::eof ? std::string("the device closed the connection")
                                      : ec.message());
    return;
  }
  driver_.Sync();
  const wire::ByteView bytes(read_buf_.data(), n);
  stats_.device_read_bytes += n;
  // Recorded by the host link's observer as it delivers them.
  transport::Link& link = server_->link();
  link.Write(bytes);
  stats_.peak_to_host_bytes = std::max(stats_.peak_to_host_bytes, link.queued_bytes());
  NoteLinkLosses();
  if (const auto change = follower_.OnDeviceBytes(bytes)) {
    recorder_->SetDialectAfter(stats_.device_read_bytes - n + change->offset, change->dialect);
    ChangeLine(change->baud, "the device acknowledged a switch to " +
                                 std::string(wire::ProtocolName(change->dialect)));
  }
  ReadDevice();
  driver_.Kick();
}

void Tap::ToDevice(wire::ByteView bytes) {
  follower_.OnHostBytes(bytes);
  if (device_stream_ == nullptr) {
    stats_.dropped_bytes += bytes.size();
    lost_to_device_unrecorded_ += bytes.size();
    if (!drop_logged_) {
      drop_logged_ = true;
      log_("the device is away: dropping what the host sends until it is back");
    }
    return;
  }
  pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  stats_.peak_to_device_bytes = std::max(stats_.peak_to_device_bytes, to_device_queued());
  // Flow control: the host's writes wait in the kernel until the device
  // has taken some of what is held for it.
  if (to_device_queued() >= config_.max_queue_bytes) server_->link().HoldReading(true);
  PumpDevice();
}

void Tap::PumpDevice() {
  if (writing_ || device_stream_ == nullptr || stopped_) return;
  if (in_write_off_ == in_write_.size()) {
    if (pending_.empty()) return;
    in_write_.swap(pending_);
    pending_.clear();
    in_write_off_ = 0;
  }
  writing_ = true;
  // Written in steps, each recorded as it is delivered.
  device_stream_->AsyncWriteSome(
      asio::buffer(in_write_.data() + in_write_off_, in_write_.size() - in_write_off_),
      [this, weak = std::weak_ptr<bool>(alive_), gen = device_gen_](const ErrorCode& ec, size_t n) {
        if (weak.expired() || gen != device_gen_ || stopped_) return;
        writing_ = false;
        if (n > 0) {
          recorder_->Traffic(driver_.NowNs(), /*host=*/true,
                             wire::ByteView(in_write_.data() + in_write_off_, n));
          stats_.host_bytes += n;
          in_write_off_ += n;
        }
        if (ec) {
          DeviceLost("write failed: " + ec.message());
          return;
        }
        if (to_device_queued() < config_.max_queue_bytes) server_->link().HoldReading(false);
        PumpDevice();
        driver_.Kick();
      });
}

void Tap::DeviceLost(const std::string& why) {
  if (device_stream_ == nullptr) return;
  driver_.Sync();
  ++stats_.device_losses;
  const size_t queued = to_device_queued();
  stats_.dropped_bytes += queued;
  pending_.clear();
  in_write_.clear();
  in_write_off_ = 0;
  writing_ = false;
  device_reading_ = false;
  device_held_ = false;
  device_stream_->Close();
  device_stream_.reset();
  serial_ = nullptr;
  ++device_gen_;
  drop_logged_ = false;
  log_("the device " + config_.device + " went away (" + why +
       "); the tap keeps running and looks for it again every " +
       std::to_string(config_.reopen_ns / sim::kNsPerMs) + " ms");
  Event({{"event", "device_link"}, {"detail", "lost: " + why}});
  if (queued > 0) {
    Event({{"event", "lost"},
           {"to", "device"},
           {"bytes", queued},
           {"detail", "host bytes queued for the device when it went away"}});
  }
  // Host bytes are dropped (and counted) until the device is back.
  server_->link().HoldReading(false);
  ScheduleReopen();
  driver_.Kick();
}

void Tap::ScheduleReopen() {
  reopen_timer_ = driver_.scheduler().After(config_.reopen_ns, [this] {
    reopen_timer_ = sim::Scheduler::kNoTimer;
    if (stopped_) return;
    try {
      OpenDevice();
    } catch (const std::exception&) {
      ScheduleReopen();
      return;
    }
    log_("the device " + config_.device + " is back");
    FlushLosses();
    Event({{"event", "device_link"}, {"detail", "open"}});
    ReadDevice();
  });
}

void Tap::ChangeLine(uint32_t baud, std::string_view why) {
  if (baud == baud_) return;
  baud_ = baud;
  ++stats_.line_changes;
  std::string result = "followed";
  if (serial_ != nullptr) {
    if (auto error = serial_->SetBaud(baud)) {
      result = "not followed: " + *error;
      log_("cannot set the device's port to " + std::to_string(baud) + " baud: " + *error);
    }
  } else {
    result = "nothing to set on a TCP device";
  }
  log_("line rate now " + std::to_string(baud) + " baud: " + std::string(why));
  Event({{"event", "line_rate"}, {"baud", baud}, {"detail", std::string(why)}, {"serial", result}});
}

void Tap::PollHostLine() {
  poll_timer_ = sim::Scheduler::kNoTimer;
  transport::PtyPort* pty = server_ ? server_->pty() : nullptr;
  if (stopped_ || pty == nullptr) return;
  const uint32_t b = pty->LineBaud();
  if (b != 0 && b != host_line_seen_) {
    host_line_seen_ = b;
    ChangeLine(b, "the host set its port to " + std::to_string(b) + " baud");
  }
  poll_timer_ = driver_.scheduler().After(config_.poll_ns, [this] { PollHostLine(); });
}

void Tap::Event(nlohmann::json event) {
  // The wall clock: never less than any time recorded before (NowNs).
  event["t_ns"] = driver_.NowNs();
  recorder_->Event(std::move(event));
}

bool Tap::Stop(std::string* error) {
  if (stopped_) return true;
  stopped_ = true;
  driver_.scheduler().Cancel(poll_timer_);
  driver_.scheduler().Cancel(reopen_timer_);
  if (server_ && started_) {
    // What was taken in and is still held is lost with the tap: counted and
    // recorded, never as traffic.
    NoteLinkLosses();
    FlushLosses();
    const size_t to_host = server_->link().undelivered_bytes();
    stats_.lost_to_host_bytes += to_host;
    lost_to_host_unrecorded_ += to_host;
    stats_.dropped_bytes += to_device_queued();
    lost_to_device_unrecorded_ += to_device_queued();
    if (lost_to_host_unrecorded_ > 0) {
      Event({{"event", "lost"},
             {"to", "host"},
             {"bytes", lost_to_host_unrecorded_},
             {"detail", "device output the host had not taken when the tap stopped"}});
      lost_to_host_unrecorded_ = 0;
    }
    if (lost_to_device_unrecorded_ > 0) {
      Event({{"event", "lost"},
             {"to", "device"},
             {"bytes", lost_to_device_unrecorded_},
             {"detail", "host bytes the device had not taken when the tap stopped"}});
      lost_to_device_unrecorded_ = 0;
    }
  }
  if (server_) server_->Stop();
  if (device_stream_) device_stream_->Close();
  device_stream_.reset();
  serial_ = nullptr;
  std::string e;
  const bool recorded = recorder_ == nullptr || recorder_->Finish(&e);
  if (!writer_) return true;
  if (!writer_->Finish(recorded ? &e : nullptr) || !recorded) {
    if (error) *error = e;
    return false;
  }
  return true;
}

int RunTap(TapConfig config, transport::LogFn log) {
  if (!log) log = transport::LogToStderr;
  asio::io_context io;
  sim::Scheduler scheduler;
  transport::RealtimeDriver driver(io, scheduler);
  // Caught before the PTY link exists, so a signal sent as soon as it
  // appears still completes the recording.
  asio::signal_set signals(io, SIGINT, SIGTERM, SIGHUP);
  std::unique_ptr<Tap> tap;
  try {
    tap = std::make_unique<Tap>(driver, config, log);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mocosim tap: %s\n", e.what());
    return 2;
  }
  int code = 0;
  signals.async_wait([&](const ErrorCode& ec, int sig) {
    if (ec) return;
    // Stopped behind the completions already queued (twice: those of the
    // handler running as the signal came are queued when it ends), so that
    // bytes the kernel took are recorded as delivered, not lost (tap.h).
    asio::post(io, [&, sig] {
      asio::post(io, [&, sig] {
        log(std::string("stopping on ") + (sig == SIGINT   ? "SIGINT"
                                           : sig == SIGHUP ? "SIGHUP"
                                                           : "SIGTERM"));
        std::string error;
        if (!tap->Stop(&error)) {
          log("recording not completed: " + error);
          code = 1;
        } else if (tap->writer() != nullptr) {
          log("recorded " + tap->writer()->path().string());
        }
        driver.Stop();
        io.stop();
      });
    });
  });
  tap->Start();
  driver.Start();
  log("tapping " + config.device + " (" + std::to_string(tap->baud()) + " baud) for host " +
      tap->HostWhere() +
      (config.record_path.empty() ? std::string() : "; recording to " + config.record_path) +
      "; Ctrl-C stops");
  io.run();
  return code;
}

}  // namespace moco::serve
