// The session logic shared by every transport: reader, writer with an
// outgoing queue, line pacing, link faults and the recording tap.
#include "transport/link.h"

#include <algorithm>
#include <iostream>

namespace moco::transport {

void LogToStderr(std::string_view line) { std::cerr << "mocosim: " << line << '\n'; }

Link::Link(RealtimeDriver& driver, LinkOptions options)
    : driver_(driver),
      scheduler_(driver.scheduler()),
      options_(std::move(options)),
      faults_(options_.faults) {
  if (!options_.log) options_.log = LogToStderr;
}

Link::~Link() {
  Stop();
  alive_.reset();
}

void Link::Log(std::string_view line) const {
  std::string s = options_.name;
  s += ": ";
  s += line;
  options_.log(s);
}

void Link::Event(std::string_view kind, std::string_view detail) {
  if (options_.observer != nullptr) {
    options_.observer->OnLinkEvent(scheduler_.Now(), kind, detail);
  }
}

void Link::CancelTimer(sim::Scheduler::TimerId& id) {
  if (id != sim::Scheduler::kNoTimer) scheduler_.Cancel(id);
  id = sim::Scheduler::kNoTimer;
}

ByteStream::Handler Link::Guard(void (Link::*member)(const ErrorCode&, size_t)) {
  return [this, weak = std::weak_ptr<bool>(alive_), gen = stream_gen_, member](const ErrorCode& ec,
                                                                               size_t n) {
    if (weak.expired() || gen != stream_gen_) return;
    (this->*member)(ec, n);
  };
}

void Link::SetDevice(devices::Device* device) {
  if (stopped_) return;
  if (device_ != nullptr && device_ != device) device_->SetLineSwitchListener(nullptr);
  device_ = device;
  if (device_ != nullptr) {
    device_->SetLineSwitchListener(
        [this, weak = std::weak_ptr<bool>(alive_)](const devices::LineSwitch& change) {
          if (!weak.expired()) OnLineSwitch(change);
        });
  }
  if (device_ == nullptr) {
    in_.clear();
    CancelTimer(in_wake_);
    return;
  }
  ApplyLine(/*always=*/true);
  if (host_open_ && options_.report_host_link) device_->OnHostLink(true);
  StartRead();
}

// ---- Device -> host ---------------------------------------------------------

void Link::ApplyLine(bool always) {
  const devices::DeviceLine line = device_->Line();
  const devices::UsbBridge bridge = options_.pacing ? line.bridge : devices::UsbBridge::None();
  // A CDC port has no UART: the baud rate paces nothing.
  const uint32_t rate =
      options_.pacing && (!bridge.active() || bridge.uart_paced) ? line.serial.BytesPerSecond() : 0;
  if (always || rate != line_rate_) {
    line_rate_ = rate;
    in_pacer_ = LinePacer(rate);
    out_pacer_ = LinePacer(rate);
  }
  if (always || bridge != bridge_pacer_.bridge()) {
    UnbridgeAll();  // bytes held by the old bridge pass through the new one
    bridge_pacer_ = UsbBridgePacer(bridge);
  }
}

void Link::OnLineSwitch(const devices::LineSwitch& change) {
  if (stopped_ || device_ == nullptr) return;
  // The pacers follow the new line from the next byte on (a StackShot
  // switching to its DfMoco dialect's rate).
  if (options_.pacing) ApplyLine(/*always=*/false);
  if (options_.observer != nullptr) {
    options_.observer->OnLineSwitch(scheduler_.Now(), change.protocol, change.line.serial);
  }
}

void Link::Write(wire::ByteView bytes) {
  if (stopped_ || bytes.empty()) return;
  const sim::TimeNs now = scheduler_.Now();
  stats_.bytes_from_device += bytes.size();
  if (options_.observer != nullptr) options_.observer->OnTraffic(now, Direction::kToHost, bytes);
  if (now < cut_until_ns_) {
    stats_.cut_dropped += bytes.size();
    return;
  }
  if (!options_.hold_while_closed && !host_open_) {
    stats_.discarded += bytes.size();
    return;
  }
  if (Straight(Direction::kToHost) && out_.empty() && !writing_ && host_open_) {
    // Nothing waits before these bytes and nothing delays them: what
    // PumpWriter would take from the queue at once goes to the stream now.
    faults_.CountPassed(Direction::kToHost, bytes.size());
    CancelTimer(out_wake_);
    const size_t n = std::min({bytes.size(), WriteChunk(), options_.max_queue_bytes});
    write_buf_.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    for (uint8_t b : bytes.subspan(n)) Enqueue(now, b);
    if (!write_buf_.empty()) StartWrite();
    return;
  }
  for (const TimedBytes& chunk : faults_.Apply(Direction::kToHost, bytes, now)) {
    for (uint8_t b : chunk.bytes) Enqueue(chunk.at_ns, b);
  }
  PumpWriter();
}

void Link::Enqueue(sim::TimeNs ready_ns, uint8_t byte) {
  if (queued_bytes() >= options_.max_queue_bytes) {
    ++stats_.overflowed;
    if (!overflow_logged_) {
      overflow_logged_ = true;
      Log("outgoing queue full (" + std::to_string(options_.max_queue_bytes) +
          " bytes, no host reading): dropping new device output");
    }
    return;
  }
  out_.push_back({ready_ns, byte});
}

size_t Link::WriteChunk() const {
  return options_.max_write_bytes == 0 ? kMaxWriteChunk
                                       : std::min(options_.max_write_bytes, kMaxWriteChunk);
}

void Link::StartWrite() {
  writing_ = true;
  stream_->AsyncWriteAll(asio::buffer(write_buf_), Guard(&Link::OnWritten));
}

sim::TimeNs Link::ClockOutUart(sim::TimeNs now, bool to_bridge) {
  // The UART sends each byte as its stop bit ends: into the bridge, or with
  // no bridge straight into the next write (at most a chunk of it).
  const size_t chunk = WriteChunk();
  while (!out_.empty() && (to_bridge || write_buf_.size() < chunk)) {
    const sim::TimeNs ready = std::max(out_.front().ready_ns, send_floor_ns_);
    const sim::TimeNs due = out_pacer_.DueTime(ready);
    if (due > now) return due;
    out_pacer_.Take(ready);
    if (to_bridge) {
      bridged_.push_back({due, out_.front().byte});
    } else {
      write_buf_.push_back(out_.front().byte);
    }
    out_.pop_front();
  }
  return sim::kTimeNever;
}

sim::TimeNs Link::TakeBridged(sim::TimeNs now) {
  sim::TimeNs next = ClockOutUart(now, /*to_bridge=*/true);
  // The bridge sends whole packets: a host never sees one trickle in.
  const size_t chunk = WriteChunk();
  const auto arrival = [this](size_t i) { return bridged_[i].ready_ns; };
  while (!bridged_.empty() && write_buf_.size() < chunk) {
    const UsbBridgePacer::Packet packet =
        bridge_pacer_.Next(bridged_.size(), arrival, send_floor_ns_);
    if (packet.at_ns > now) {
      next = std::min(next, packet.at_ns);
      break;
    }
    bridge_pacer_.Sent(packet);
    for (size_t i = 0; i < packet.bytes; ++i) {
      write_buf_.push_back(bridged_.front().byte);
      bridged_.pop_front();
    }
  }
  return next;
}

void Link::UnbridgeAll() {
  while (!bridged_.empty()) {
    out_.push_front(bridged_.back());
    bridged_.pop_back();
  }
}

void Link::PumpWriter() {
  if (stopped_ || writing_ || !host_open_ || (out_.empty() && bridged_.empty())) return;
  CancelTimer(out_wake_);
  const sim::TimeNs now = driver_.NowNs();
  write_buf_.clear();
  const sim::TimeNs next =
      bridge_pacer_.active() ? TakeBridged(now) : ClockOutUart(now, /*to_bridge=*/false);
  if (!write_buf_.empty()) {
    StartWrite();
  } else if (next != sim::kTimeNever) {
    out_wake_ = scheduler_.At(next, [this] {
      out_wake_ = sim::Scheduler::kNoTimer;
      PumpWriter();
    });
  }
}

void Link::OnWritten(const ErrorCode& ec, size_t n) {
  writing_ = false;
  if (ec) {
    StreamEnded("write failed: " + ec.message());
    driver_.Kick();
    return;
  }
  stats_.bytes_to_host += n;
  // Bytes written again after a reclaim were reported the first time.
  const size_t again = std::min(n, redelivered_);
  redelivered_ -= again;
  if (options_.observer != nullptr && n > again) {
    options_.observer->OnDelivered(driver_.NowNs(), Direction::kToHost,
                                   wire::ByteView(write_buf_.data() + again, n - again));
  }
  write_buf_.clear();
  if (!host_present_) Reclaim();
  PumpWriter();
  StartRead();  // resumes reading held back by a full outgoing queue
  NotifyDrain();
  driver_.Kick();
}

void Link::NotifyDrain() {
  if (!stopped_ && options_.on_drain) options_.on_drain();
}

void Link::DroppedFromHead(size_t n) { redelivered_ -= std::min(n, redelivered_); }

void Link::HoldReading(bool hold) {
  if (hold == hold_reading_) return;
  hold_reading_ = hold;
  if (!hold) StartRead();
}

// ---- Host -> device ---------------------------------------------------------

void Link::StartRead() {
  if (stopped_ || reading_ || hold_reading_ || !stream_ || device_ == nullptr ||
      in_.size() >= kMaxInboundBytes) {
    return;
  }
  // Back-pressure: while the host leaves half the outgoing queue unread, its
  // requests wait in the kernel (its writes block) instead of making answers
  // that would overflow the queue and be lost.
  if (host_open_ && queued_bytes() >= options_.max_queue_bytes / 2) return;
  reading_ = true;
  stream_->AsyncReadSome(asio::buffer(read_buf_), Guard(&Link::OnRead));
}

void Link::OnRead(const ErrorCode& ec, size_t n) {
  if (ec) {
    reading_ = false;
    StreamEnded(ec == asio::error::eof ? std::string("host closed the connection")
                                       : "read failed: " + ec.message());
    driver_.Kick();
    return;
  }
  // read_buf_ still holds this read's bytes: reading_ stays set until they are
  // queued, so that a timer run by Sync() (the inbound wake calls StartRead)
  // cannot start the next read into the same buffer. Asio may fill the buffer
  // of a new read at once (a speculative read), which would overwrite bytes
  // not yet consumed: host bytes lost, repeated and reordered.
  const uint64_t gen = stream_gen_;
  const sim::TimeNs now = driver_.Sync();
  if (gen != stream_gen_ || stopped_) {
    // A timer closed this stream (a link cut, a stop): its bytes go with it,
    // and read_buf_ may already belong to the next stream's read.
    stats_.bytes_from_host += n;
    stats_.cut_dropped += n;
    driver_.Kick();
    return;
  }
  stats_.bytes_from_host += n;
  // A read that took (nearly) the whole buffer most likely left bytes
  // behind, where the kernel may not count them yet: a PTY's line discipline
  // holds 4095 bytes, and the rest waits in its flip buffer until a kernel
  // worker moves it. Until the next read, host bytes count as waiting.
  last_read_full_ = n + 1 >= read_buf_.size();
  const wire::ByteView bytes(read_buf_.data(), n);
  if (now < cut_until_ns_) {
    stats_.cut_dropped += n;
  } else {
    if (Straight(Direction::kToDevice) && in_.empty()) {
      // Unpaced, no faults, nothing waiting: due now, as DeliverInbound
      // would find them, and handed on without the per-byte queue.
      faults_.CountPassed(Direction::kToDevice, n);
      CancelTimer(in_wake_);
      if (device_ != nullptr) {
        stats_.bytes_to_device += n;
        if (options_.observer != nullptr) {
          options_.observer->OnTraffic(now, Direction::kToDevice, bytes);
        }
        device_->OnHostBytes(bytes);
      }
    } else {
      for (const TimedBytes& chunk : faults_.Apply(Direction::kToDevice, bytes, now)) {
        for (uint8_t b : chunk.bytes) in_.push_back({in_pacer_.Take(chunk.at_ns), b});
      }
      DeliverInbound();
    }
  }
  reading_ = false;
  StartRead();
  driver_.Kick();
}

bool Link::HostBytesWaiting() {
  if (!in_.empty() || last_read_full_) return true;
  return stream_ != nullptr && !stopped_ && stream_->Available() > 0;
}

void Link::DeliverInbound() {
  CancelTimer(in_wake_);
  if (device_ == nullptr) {
    in_.clear();
    return;
  }
  const sim::TimeNs now = scheduler_.Now();
  wire::Bytes chunk;
  while (!in_.empty() && in_.front().due_ns <= now) {
    chunk.push_back(in_.front().byte);
    in_.pop_front();
  }
  if (!in_.empty()) {
    in_wake_ = scheduler_.At(in_.front().due_ns, [this] {
      in_wake_ = sim::Scheduler::kNoTimer;
      DeliverInbound();
      StartRead();
    });
  }
  if (!chunk.empty()) {
    stats_.bytes_to_device += chunk.size();
    if (options_.observer != nullptr) {
      options_.observer->OnTraffic(now, Direction::kToDevice, chunk);
    }
    device_->OnHostBytes(chunk);
  }
}

// ---- Streams and host presence ---------------------------------------------

void Link::Attach(std::unique_ptr<ByteStream> stream,
                  std::function<void(const std::string&)> on_end) {
  if (stopped_) {
    stream->Close();
    return;
  }
  driver_.Sync();
  DetachInternal();
  stream_ = std::move(stream);
  on_end_ = std::move(on_end);
  ++stream_gen_;
  ++stats_.connections;
  UpdateHostOpen();
  StartRead();
  PumpWriter();
  driver_.Kick();
}

void Link::Detach() {
  // Once stopped there is nothing attached, and the clock must not run: the
  // device may be gone with its timers still pending.
  if (stopped_) return;
  driver_.Sync();
  DetachInternal();
  driver_.Kick();
}

void Link::DetachInternal() {
  if (!stream_) return;
  stream_->Close();
  stream_.reset();
  ++stream_gen_;
  reading_ = false;
  last_read_full_ = false;
  if (writing_) {
    // The write in flight goes with the stream: the host never got it whole.
    stats_.discarded += write_buf_.size();
    DroppedFromHead(write_buf_.size());
  }
  writing_ = false;
  write_buf_.clear();
  on_end_ = nullptr;
  CancelTimer(out_wake_);
  UpdateHostOpen();
}

void Link::StreamEnded(const std::string& reason) {
  auto on_end = std::move(on_end_);
  driver_.Sync();
  DetachInternal();
  if (on_end) on_end(reason);
}

void Link::SetHostPresent(bool present) {
  if (present == host_present_) return;
  driver_.Sync();
  host_present_ = present;
  UpdateHostOpen();
  driver_.Kick();
}

void Link::UpdateHostOpen() {
  const bool open = stream_ != nullptr && host_present_ && !stopped_;
  if (open == host_open_) return;
  host_open_ = open;
  Event("host_link", open ? "open" : "closed");
  if (open) {
    // Bytes held while the host was away start a fresh burst now.
    send_floor_ns_ = driver_.NowNs();
    out_pacer_.Reset();
    reclaim_pos_ = 0;
    CancelTimer(reclaim_timer_);
  } else {
    CancelTimer(out_wake_);
    UnbridgeAll();
    if (!options_.hold_while_closed) {
      stats_.discarded += out_.size();
      out_.clear();
      redelivered_ = std::min(redelivered_, writing_ ? write_buf_.size() : 0);
    } else if (stream_ != nullptr) {
      if (!writing_) Reclaim();
      ScheduleReclaimRetry();
    }
  }
  if (device_ != nullptr && options_.report_host_link) device_->OnHostLink(open);
  if (open) PumpWriter();
  NotifyDrain();
}

void Link::ScheduleReclaimRetry() {
  CancelTimer(reclaim_timer_);
  reclaim_timer_ = scheduler_.After(kReclaimRetryNs, [this] {
    reclaim_timer_ = sim::Scheduler::kNoTimer;
    // A write the departed host's full buffer holds up completes only once
    // the buffer is read: reclaiming what it holds (older bytes than the
    // write's) lets it finish, and OnWritten reclaims what it wrote, in order.
    Reclaim();
    if (writing_ && !host_present_ && stream_ != nullptr && !stopped_) ScheduleReclaimRetry();
  });
}

void Link::Reclaim() {
  if (!stream_ || host_present_) return;
  const wire::Bytes back = stream_->Reclaim();
  if (back.empty()) return;
  const sim::TimeNs now = scheduler_.Now();
  auto pos = out_.begin() + static_cast<std::ptrdiff_t>(std::min(reclaim_pos_, out_.size()));
  for (uint8_t b : back) {
    pos = out_.insert(pos, OutByte{now, b});
    ++pos;
  }
  reclaim_pos_ += back.size();
  redelivered_ += back.size();
  stats_.reclaimed += back.size();
}

// ---- Faults and lifecycle ---------------------------------------------------

void Link::Cut(sim::TimeNs duration_ns, bool close_stream) {
  if (stopped_) return;
  const sim::TimeNs now = driver_.Sync();
  cut_until_ns_ = std::max(cut_until_ns_, now + std::max<sim::TimeNs>(duration_ns, 0));
  stats_.cut_dropped += in_.size() + out_.size() + bridged_.size();
  in_.clear();
  out_.clear();
  bridged_.clear();
  reclaim_pos_ = 0;
  redelivered_ = std::min(redelivered_, writing_ ? write_buf_.size() : 0);
  CancelTimer(in_wake_);
  CancelTimer(out_wake_);
  Event("link_fault", "cut " + std::to_string(duration_ns));
  Log("link cut for " + std::to_string(duration_ns / sim::kNsPerMs) + " ms");
  if (close_stream) DetachInternal();
  StartRead();
  driver_.Kick();
}

void Link::PowerCycle(sim::TimeNs off_ns) {
  if (stopped_ || device_ == nullptr) return;
  driver_.Sync();
  Event("power_cycle", "off " + std::to_string(off_ns));
  Log("power cycle: off for " + std::to_string(off_ns / sim::kNsPerMs) + " ms");
  CancelTimer(power_on_timer_);
  device_->PowerOff();
  power_on_timer_ = scheduler_.After(off_ns, [this] {
    power_on_timer_ = sim::Scheduler::kNoTimer;
    if (device_ != nullptr) device_->PowerOn();
  });
  driver_.Kick();
}

void Link::SetFaults(const FaultConfig& config) {
  if (stopped_) return;
  faults_ = FaultInjector(config);
  Event("link_fault", config.Any() ? "faults on" : "faults off");
  Log(config.Any() ? "fault injection on" : "fault injection off");
}

void Link::Stop() {
  if (stopped_) return;
  stopped_ = true;
  // Shutting down is not a host event: the device and the observer may
  // already be gone (they are usually built after the link, so die first).
  device_ = nullptr;
  options_.observer = nullptr;
  options_.on_drain = nullptr;
  CancelTimer(in_wake_);
  CancelTimer(out_wake_);
  CancelTimer(reclaim_timer_);
  CancelTimer(power_on_timer_);
  DetachInternal();
  in_.clear();
  out_.clear();
  bridged_.clear();
}

}  // namespace moco::transport
