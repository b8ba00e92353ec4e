// The session logic shared by every transport (ARCHITECTURE house style 9):
// a reader that hands host bytes to the device, a writer that drains the
// device's outgoing queue to the host at the device's line rate, link faults
// and the recording tap. PTY and TCP ports only supply a connected stream.
#ifndef MOCO_TRANSPORT_LINK_H_
#define MOCO_TRANSPORT_LINK_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "devices/device.h"
#include "sim/scheduler.h"
#include "transport/asio.h"
#include "transport/line_pacer.h"
#include "transport/link_faults.h"
#include "transport/realtime_driver.h"
#include "transport/traffic.h"
#include "transport/usb_bridge_pacer.h"
#include "wire/bytes.h"

namespace moco::transport {

// One connected, full-duplex byte stream (a PTY master, a TCP socket).
// Completion handlers run on the io thread; closing the stream completes
// pending operations with an error.
class ByteStream {
 public:
  using Handler = std::function<void(const ErrorCode&, size_t)>;
  virtual ~ByteStream() = default;
  // REQUIRES: at most one read and one write pending; buffers outlive them.
  virtual void AsyncReadSome(asio::mutable_buffer buffer, Handler handler) = 0;
  virtual void AsyncWriteAll(asio::const_buffer buffer, Handler handler) = 0;
  // Writes some of `buffer` (at least one byte unless an error ends it) and
  // reports how many: a caller that must know which bytes left (the tap
  // records bytes as they are delivered) writes in such steps. Default: all.
  virtual void AsyncWriteSome(asio::const_buffer buffer, Handler handler) {
    AsyncWriteAll(buffer, std::move(handler));
  }
  virtual void Close() = 0;
  // Takes back bytes already written but not yet read by the far end, when the
  // stream can (a PTY whose host closed the port); oldest first.
  virtual wire::Bytes Reclaim() { return {}; }
  // "127.0.0.1:51234", "/dev/pts/3": for log lines.
  virtual std::string PeerName() const = 0;
  // Bytes the far end wrote that wait to be read (the kernel's count); 0 when
  // unknown.
  virtual size_t Available() { return 0; }
};

// Adapts an Asio stream (tcp::socket, posix::stream_descriptor) to ByteStream.
template <typename Stream>
class AsioByteStream : public ByteStream {
 public:
  AsioByteStream(Stream stream, std::string peer)
      : stream_(std::move(stream)), peer_(std::move(peer)) {}
  void AsyncReadSome(asio::mutable_buffer buffer, Handler handler) override {
    stream_.async_read_some(buffer, std::move(handler));
  }
  void AsyncWriteAll(asio::const_buffer buffer, Handler handler) override {
    asio::async_write(stream_, buffer, std::move(handler));
  }
  void AsyncWriteSome(asio::const_buffer buffer, Handler handler) override {
    stream_.async_write_some(buffer, std::move(handler));
  }
  void Close() override {
    ErrorCode ignored;
    stream_.close(ignored);
  }
  std::string PeerName() const override { return peer_; }
  size_t Available() override {
    typename Stream::bytes_readable command(true);
    ErrorCode ec;
    stream_.io_control(command, ec);
    return ec ? 0 : command.get();
  }
  Stream& stream() { return stream_; }

 private:
  Stream stream_;
  std::string peer_;
};

// Writes one log line (no trailing newline). The default writes to stderr.
using LogFn = std::function<void(std::string_view)>;
void LogToStderr(std::string_view line);

struct LinkOptions {
  // Pace both directions at the device's Line().serial.BytesPerSecond().
  bool pacing = true;
  // Device output waiting for the host is kept up to this many bytes; beyond
  // it, newly written bytes are dropped and counted (LinkStats::overflowed).
  size_t max_queue_bytes = 256 * 1024;
  // Keep device output while no host is attached or present (a PTY: delivered
  // after the host reopens); when false it is discarded (a TCP device with no
  // client), and a new connection starts with an empty queue.
  bool hold_while_closed = true;
  // Tell the device Device::OnHostLink on host open/close.
  bool report_host_link = true;
  // Most device bytes handed to the stream in one write (StackShot Wi-Fi:
  // 1000, "The maximum size of a single packet"). 0 or above the link's own
  // chunk (4096): the chunk.
  size_t max_write_bytes = 0;
  FaultConfig faults;
  TrafficObserver* observer = nullptr;  // not owned; must outlive the link
  // Called on the io thread when the outgoing queue may have room again or
  // the host came or went (a write to the host completed, a host attached or
  // detached): a writer that holds its source back while queued_bytes() is
  // near max_queue_bytes (the tap, docs/tap.md "Flow control") reads on.
  std::function<void()> on_drain;
  LogFn log = LogToStderr;
  std::string name = "link";  // prefix of log lines, e.g. "pty /tmp/dmc16"
};

struct LinkStats {
  uint64_t bytes_from_host = 0;    // read from streams
  uint64_t bytes_to_device = 0;    // handed to the device
  uint64_t bytes_from_device = 0;  // written by the device
  uint64_t bytes_to_host = 0;      // written to streams
  uint64_t overflowed = 0;         // dropped: queue full
  uint64_t discarded = 0;          // dropped: no host and !hold_while_closed, queue cleared, or a
                                   // write in flight when the host's stream ended
  uint64_t cut_dropped = 0;        // dropped during a link cut
  uint64_t reclaimed = 0;          // taken back from a closed PTY and re-queued
  uint64_t connections = 0;        // streams attached
};

// The device end of a transport. Construct it, give it to the device as its
// ByteSink, then SetDevice(); a port Attach()es streams to it.
//
// Host bytes: read from the stream, passed through faults, paced at the line
// rate, handed to Device::OnHostBytes at the scheduler time they are due,
// after which the driver is kicked. Device bytes: stamped with the scheduler
// time of the write, passed through faults, queued, and written to the stream
// when the line rate allows (a byte no earlier than the end of its own
// character time) and the host is present. Behind a USB serial bridge
// (DeviceLine::bridge) the bytes the UART completed wait in the bridge and
// are written a packet at a time, when the bridge would send it; a CDC port
// has no UART, so neither direction is paced at the line rate.
//
// The driver must outlive the link. The device and the observer must outlive
// the link's service: until Stop() (or the destructor, which stops), neither
// of which calls them, so they may be destroyed before the link itself.
// Destroying the link is safe with handlers pending (they then do nothing).
// Single-threaded: the io thread only.
class Link final : public devices::ByteSink {
 public:
  Link(RealtimeDriver& driver, LinkOptions options);
  ~Link() override;
  Link(const Link&) = delete;
  Link& operator=(const Link&) = delete;

  // Sets the device served (nullptr: none; host bytes are then dropped) and
  // starts reading if a stream is attached.
  void SetDevice(devices::Device* device);

  // devices::ByteSink: device output. Never blocks.
  void Write(wire::ByteView bytes) override;
  // devices::ByteSink: host bytes not yet handed to the device: in the paced
  // inbound queue, or in the kernel while this end is behind (the io thread
  // busy with other devices, or reading held back by a full outgoing queue).
  bool HostBytesWaiting() override;

  // Serves `stream` from now on. `on_end` runs (on the io thread) when the
  // stream ends by itself (EOF or an error, with the reason), not after
  // Detach(). REQUIRES: !attached().
  void Attach(std::unique_ptr<ByteStream> stream,
              std::function<void(const std::string& reason)> on_end = nullptr);
  // Closes and forgets the current stream, if any.
  void Detach();
  bool attached() const { return stream_ != nullptr; }

  // Whether a host has the far end open (a PTY's host opening or closing the
  // port). Bytes are written to the stream only while present; on a change to
  // absent, bytes the host did not read are reclaimed and re-queued in order.
  // Starts true.
  void SetHostPresent(bool present);
  bool host_open() const { return host_open_; }

  // Link cut: for duration_ns nothing crosses in either direction (bytes
  // queued or arriving meanwhile are dropped), and the current stream is
  // closed when `close_stream` (TCP: the host sees a disconnect).
  void Cut(sim::TimeNs duration_ns, bool close_stream);
  // Whether a cut is in force now (by the wall clock).
  bool cut_active() { return driver_.NowNs() < cut_until_ns_; }
  // Power-cycles the device: PowerOff() now, PowerOn() after off_ns.
  void PowerCycle(sim::TimeNs off_ns);
  // Replaces the fault injection from now on (a config with no fault turns it
  // off). Counts and generators restart from the new config's seed; bytes
  // already delayed keep their release times. REQUIRES: !config.Validate().
  void SetFaults(const FaultConfig& config);

  // Holds back (true) or resumes (false) reading from the host: the far side
  // of a proxy cannot take more yet, so the host's writes wait in the kernel
  // (its writes block), as a UART's would. Starts false.
  void HoldReading(bool hold);
  bool reading_held() const { return hold_reading_; }

  // Closes the stream, cancels the link's timers and stops serving, without
  // calling the device or the observer. Idempotent.
  void Stop();

  const LinkStats& stats() const { return stats_; }
  const FaultInjector& faults() const { return faults_; }
  size_t queued_bytes() const { return out_.size() + bridged_.size() + write_buf_.size(); }
  // Queued bytes never reported delivered (queued_bytes() less those taken
  // back from a PTY the host closed unread).
  size_t undelivered_bytes() const { return queued_bytes() - redelivered_; }
  const LinePacer& out_pacer() const { return out_pacer_; }
  const UsbBridgePacer& bridge_pacer() const { return bridge_pacer_; }
  RealtimeDriver& driver() { return driver_; }
  void Log(std::string_view line) const;

 private:
  struct OutByte {
    sim::TimeNs ready_ns;
    uint8_t byte;
  };
  struct InByte {
    sim::TimeNs due_ns;
    uint8_t byte;
  };
  static constexpr size_t kReadChunk = 4096;
  static constexpr size_t kMaxWriteChunk = 4096;
  // Host bytes read but not yet due at the device; reading pauses above it so
  // a host that outruns the line rate is held back by the kernel, as a UART is.
  static constexpr size_t kMaxInboundBytes = 4096;
  // A second reclaim pass after the host closes catches bytes that were still
  // in the PTY's flip buffer during the first.
  static constexpr sim::TimeNs kReclaimRetryNs = 20 * sim::kNsPerMs;

  // The device announced a switch of its line: pace at its rate, tell the
  // observer.
  void OnLineSwitch(const devices::LineSwitch& change);
  // Sets the pacers from the device's line: `always` resets them even when
  // the line is unchanged.
  void ApplyLine(bool always);
  // Whether bytes in `dir` pass unpaced and with no fault: they then skip
  // the per-byte queues (same result, without the per-byte work).
  bool Straight(Direction dir) const {
    return line_rate_ == 0 && (dir == Direction::kToDevice || !bridge_pacer_.active()) &&
           faults_.PassesUnchanged(dir);
  }
  // Moves the bytes whose character time has ended on the UART into the
  // bridge (to_bridge) or into write_buf_; returns when the next one ends
  // (kTimeNever: none waits, or write_buf_ holds a chunk).
  sim::TimeNs ClockOutUart(sim::TimeNs now, bool to_bridge);
  // Moves the bytes whose character time has ended into the bridge and the
  // bridge's packets that are due into write_buf_; returns when to look
  // again (kTimeNever: nothing waits).
  sim::TimeNs TakeBridged(sim::TimeNs now);
  // The bytes the bridge holds go back to the head of out_ (the host left:
  // they are sent again, in order, when it returns).
  void UnbridgeAll();
  size_t WriteChunk() const;
  void Enqueue(sim::TimeNs ready_ns, uint8_t byte);
  void StartWrite();
  void StartRead();
  void OnRead(const ErrorCode& ec, size_t n);
  void DeliverInbound();
  void PumpWriter();
  void OnWritten(const ErrorCode& ec, size_t n);
  void StreamEnded(const std::string& reason);
  void DetachInternal();
  void UpdateHostOpen();
  void Reclaim();
  // Forgets `n` bytes dropped from the head of the queue (write_buf_ first).
  void DroppedFromHead(size_t n);
  void NotifyDrain();
  // Reclaims again after kReclaimRetryNs, and on while a write is held up.
  void ScheduleReclaimRetry();
  void CancelTimer(sim::Scheduler::TimerId& id);
  void Event(std::string_view kind, std::string_view detail);
  // Wraps a stream completion handler: it does nothing once the link is gone
  // or the stream it was started on was replaced.
  ByteStream::Handler Guard(void (Link::*member)(const ErrorCode&, size_t));

  RealtimeDriver& driver_;
  sim::Scheduler& scheduler_;
  LinkOptions options_;
  devices::Device* device_ = nullptr;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
  bool stopped_ = false;

  std::unique_ptr<ByteStream> stream_;
  std::function<void(const std::string&)> on_end_;
  uint64_t stream_gen_ = 0;
  bool host_present_ = true;
  bool host_open_ = false;

  FaultInjector faults_;
  sim::TimeNs cut_until_ns_ = 0;

  // Host -> device.
  std::array<uint8_t, kReadChunk> read_buf_{};
  bool reading_ = false;
  bool hold_reading_ = false;
  bool last_read_full_ = false;  // the last read took the whole buffer (HostBytesWaiting)
  std::deque<InByte> in_;
  uint32_t line_rate_ = 0;  // bytes/s the pacers run at (0: unpaced)
  LinePacer in_pacer_;
  sim::Scheduler::TimerId in_wake_ = sim::Scheduler::kNoTimer;

  // Device -> host.
  std::deque<OutByte> out_;
  // Behind a USB bridge: bytes the UART completed (ready_ns: when), waiting
  // for their packet. They come after write_buf_ and before out_.
  std::deque<OutByte> bridged_;
  UsbBridgePacer bridge_pacer_;
  wire::Bytes write_buf_;
  bool writing_ = false;
  LinePacer out_pacer_;
  sim::TimeNs send_floor_ns_ = 0;  // bytes are not sent before the host (re)opened
  size_t reclaim_pos_ = 0;         // where the next reclaimed bytes go in out_
  // Bytes at the head of write_buf_ + out_ already reported delivered
  // (TrafficObserver::OnDelivered) once: taken back from a PTY the host
  // closed without reading them. They come first in the order written.
  size_t redelivered_ = 0;
  sim::Scheduler::TimerId out_wake_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId reclaim_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId power_on_timer_ = sim::Scheduler::kNoTimer;
  bool overflow_logged_ = false;

  LinkStats stats_;
};

}  // namespace moco::transport

#endif  // MOCO_TRANSPORT_LINK_H_
