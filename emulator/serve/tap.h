// `mocosim tap` (docs/tap.md): a recording proxy between a host and a real
// device. The host side is a PTY with a stable symlink or a TCP port (the
// emulator's own transports, unpaced); the device side a serial port or a TCP
// address. Bytes pass unchanged both ways and are recorded with their arrival
// times, and their decoded messages, as a session (docs/sessions.md) that
// `mococheck replay`/`fuzz` and `mocosim decode`/`plot` read as they read a
// `--record`ed one.
#ifndef MOCO_SERVE_TAP_H_
#define MOCO_SERVE_TAP_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "devices/device.h"
#include "serve/tap_line_rate.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "transport/device_server.h"
#include "transport/link.h"
#include "transport/realtime_driver.h"
#include "transport/serial_stream.h"
#include "transport/traffic.h"
#include "wire/protocol.h"
#include "wire/transcript.h"

namespace moco::serve {

struct TapConfig {
  wire::Protocol protocol = wire::Protocol::kDmc;
  // The session header's "device": the model a replay builds in process
  // ("dmc16", "dfmoco-uno", "stackshot3x"); empty: the protocol's usual one.
  std::string device_model;
  // Recorded in the header as "profile" when given (the profile a replay
  // should use for this device).
  std::string profile;
  std::string host;    // "pty:/tmp/dmc16", "tcp:5000", "tcp:0.0.0.0:5000"
  std::string device;  // "serial:/dev/ttyUSB0", "/dev/ttyUSB0", "tcp:HOST:PORT"
  uint32_t baud = 0;   // 0: the protocol's line (wire::Info(protocol).line.baud)
  bool rtscts = false;
  std::string record_path;         // empty: pass bytes through without recording
  std::string note;                // the header's "note"; empty: where the tap ran
  int64_t time_tolerance_ms = 50;  // the header's tolerances.time_ms (replay)
  // How often the host PTY's line speed is looked at, and how often a
  // device that went away is looked for again.
  sim::TimeNs poll_ns = 20 * sim::kNsPerMs;
  sim::TimeNs reopen_ns = 1000 * sim::kNsPerMs;
  // Flow control (docs/tap.md "Flow control"): at most this many bytes are
  // held for each side. Past it the tap stops reading the other side until
  // the slow one takes some, so the kernel and the line hold the rest.
  size_t max_queue_bytes = 256 * 1024;
};

// Parses a device-side spec: "serial:PATH", "tcp:HOST:PORT" or a bare path
// (a serial port). On failure returns a message naming the forms accepted.
struct DeviceSpec {
  bool tcp = false;
  std::string path;  // serial
  std::string host;  // tcp
  uint16_t port = 0;
};
std::variant<DeviceSpec, std::string> ParseDeviceSpec(std::string_view spec);

// The usual device model of a protocol ("dmc16", "dfmoco-uno", "stackshot3x").
std::string DefaultTapDevice(wire::Protocol protocol);

// Bytes are counted where they are recorded: when delivered (written to the
// other side's port or socket). What was taken in and never delivered is
// counted as lost and recorded as a "lost" event with its count.
struct TapStats {
  uint64_t host_bytes = 0;          // host -> device, delivered and recorded
  uint64_t device_bytes = 0;        // device -> host, delivered and recorded
  uint64_t device_read_bytes = 0;   // read from the device
  uint64_t dropped_bytes = 0;       // host bytes lost: the device was away or went with them
  uint64_t lost_to_host_bytes = 0;  // device bytes lost: no TCP host, or the tap stopped first
  uint64_t device_losses = 0;
  uint64_t line_changes = 0;
  // The most bytes held at once for the device (read from the host, not yet
  // written) and for the host (the host link's outgoing queue): flow control
  // keeps each within TapConfig::max_queue_bytes plus one read (4 KiB).
  size_t peak_to_device_bytes = 0;
  size_t peak_to_host_bytes = 0;
};

// One tap. Construction opens both ends (the device side first, so a host
// never sees a port with nothing behind it) and the recording; Start() begins
// passing bytes. Host bytes reach the device in the order read, device bytes
// the host in the order read; each chunk is stamped with the driver's clock
// as it is delivered (header "clock": "real", t_ns from the tap's start) and
// recorded off the forwarding path: the io thread copies it into a batch and
// a writer thread decodes and writes the batch (one write per batch, at most
// about 50 ms after its first chunk). Stop() writes what is left, so a
// stopped tap's recording is complete.
//
// Flow control: neither side is read while the other's buffer in the tap is
// full (max_queue_bytes), as a serial bridge stops its UART: bytes wait in
// the kernel (and the sender's writes block) instead of being dropped, so
// memory stays bounded both ways and no byte is lost to a slow reader. Each
// chunk is recorded when it is delivered (written to the other side), so the
// recording never holds a byte that did not arrive; the few that cannot
// arrive (the device gone with bytes queued for it, a TCP host leaving, the
// tap stopped before a host read its bytes) are counted and recorded as a
// "lost" event with "to" and "bytes".
//
// Ends: the host closing and reopening its PTY (or a TCP host disconnecting
// and another connecting) never ends the tap; it is recorded as a
// "host_link" event. The device going away (EOF, an error: a USB adapter
// unplugged) is logged and recorded ("device_link" "lost: <why>"); host
// bytes are then dropped and counted, and the device is looked for again
// every reopen_ns ("device_link" "open" when back). A line-rate change
// (LineRateFollower, or the host setting another speed on the tap's PTY) is
// applied to the serial port and recorded ("line_rate" with "baud").
//
// The driver must outlive the tap. Every call comes from the driver's io
// thread; the recording's writer thread is the tap's own (started by
// Start(), joined by Stop()).
class Tap {
 public:
  // Throws std::runtime_error with a message naming the side, the problem
  // and the fix (a bad spec, a port that cannot be opened, a recording path
  // that cannot be written).
  Tap(transport::RealtimeDriver& driver, TapConfig config,
      transport::LogFn log = transport::LogToStderr);
  ~Tap();
  Tap(const Tap&) = delete;
  Tap& operator=(const Tap&) = delete;

  void Start();
  // Stops passing bytes, closes both ends (the PTY symlink removed) and
  // completes the recording (atomically). Returns false with a message when
  // the recording could not be completed. Idempotent. A write whose
  // completion has not run yet counts as not delivered ("lost"): a caller
  // stopping from outside posts Stop() behind the completions already queued
  // (RunTap posts it twice).
  bool Stop(std::string* error = nullptr);

  // "pty /tmp/dmc16 -> /dev/pts/4" or "tcp 127.0.0.1:5000".
  std::string HostWhere() const { return server_->Where(); }
  uint16_t host_tcp_port() const { return server_->tcp_port(); }
  bool device_open() const { return device_stream_ != nullptr; }
  uint32_t baud() const { return baud_; }
  TapStats stats() const;
  // Host bytes held for the device now (read, not yet written).
  size_t to_device_queued() const { return pending_.size() + in_write_.size() - in_write_off_; }
  // Flow control in force: the device is not read (the host's queue is
  // full) / the host is not read (the bytes held for the device are).
  bool device_held() const { return device_held_; }
  bool host_held() const { return server_->link().reading_held(); }
  const session::SessionWriter* writer() const { return writer_.get(); }

 private:
  class Forwarder;
  class Recorder;
  void OpenDevice();
  void DeviceLost(const std::string& why);
  void ReadDevice();
  void OnDrain();
  void NoteLinkLosses();
  void FlushLosses();
  void OnDeviceRead(const transport::ErrorCode& ec, size_t n);
  void ToDevice(wire::ByteView bytes);
  void PumpDevice();
  void ChangeLine(uint32_t baud, std::string_view why);
  void PollHostLine();
  void ScheduleReopen();
  void Event(nlohmann::json event);

  transport::RealtimeDriver& driver_;
  TapConfig config_;
  transport::LogFn log_;
  DeviceSpec spec_;
  uint32_t baud_ = 0;
  std::unique_ptr<session::SessionWriter> writer_;
  std::unique_ptr<Recorder> recorder_;
  std::unique_ptr<Forwarder> forwarder_;
  std::unique_ptr<transport::DeviceServer> server_;
  LineRateFollower follower_;

  std::unique_ptr<transport::ByteStream> device_stream_;
  transport::SerialStream* serial_ = nullptr;  // device_stream_ when it is a serial port
  uint64_t device_gen_ = 0;
  std::array<uint8_t, 4096> read_buf_{};
  wire::Bytes pending_;      // host bytes waiting for the device's write
  wire::Bytes in_write_;     // being written; in_write_off_ of it are written
  size_t in_write_off_ = 0;  // delivered (and recorded) bytes of in_write_
  bool writing_ = false;
  bool device_reading_ = false;  // a read of the device is pending
  bool device_held_ = false;     // not read: the host's queue has no room
  uint64_t link_lost_seen_ = 0;  // the host link's drops already counted
  uint64_t lost_to_host_unrecorded_ = 0;
  uint64_t lost_to_device_unrecorded_ = 0;
  bool drop_logged_ = false;

  uint32_t host_line_seen_ = 0;
  sim::Scheduler::TimerId poll_timer_ = sim::Scheduler::kNoTimer;
  sim::Scheduler::TimerId reopen_timer_ = sim::Scheduler::kNoTimer;
  bool started_ = false;
  bool stopped_ = false;
  TapStats stats_;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

// `mocosim tap`: runs a tap until SIGINT/SIGTERM/SIGHUP. Returns the exit
// code: 0 done, 1 the recording could not be completed, 2 a set-up error
// (printed).
int RunTap(TapConfig config, transport::LogFn log = transport::LogToStderr);

}  // namespace moco::serve

#endif  // MOCO_SERVE_TAP_H_
