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
  uint32_t baud = 0;   // 0: the protocol's line (DMC 115200, DFMoco 57600, StackShot 38400)
  bool rtscts = false;
  std::string record_path;         // empty: pass bytes through without recording
  std::string note;                // the header's "note"; empty: where the tap ran
  int64_t time_tolerance_ms = 50;  // the header's tolerances.time_ms (replay)
  // How often the host PTY's line speed is looked at, and how often a
  // device that went away is looked for again.
  sim::TimeNs poll_ns = 20 * sim::kNsPerMs;
  sim::TimeNs reopen_ns = 1000 * sim::kNsPerMs;
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

struct TapStats {
  uint64_t host_bytes = 0;     // host -> device, passed on
  uint64_t device_bytes = 0;   // device -> host, passed on
  uint64_t dropped_bytes = 0;  // host bytes while the device was away
  uint64_t device_losses = 0;
  uint64_t line_changes = 0;
};

// One tap. Construction opens both ends (the device side first, so a host
// never sees a port with nothing behind it) and the recording; Start() begins
// passing bytes. Host bytes reach the device in the order read, device bytes
// the host in the order read; each chunk is stamped with the driver's clock
// as it is read (header "clock": "real", t_ns from the tap's start) and
// recorded off the forwarding path: the io thread copies it into a batch and
// a writer thread decodes and writes the batch (one write per batch, at most
// about 50 ms after its first chunk). Stop() writes what is left, so a
// stopped tap's recording is complete.
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
  // the recording could not be completed. Idempotent.
  bool Stop(std::string* error = nullptr);

  // "pty /tmp/dmc16 -> /dev/pts/4" or "tcp 127.0.0.1:5000".
  std::string HostWhere() const { return server_->Where(); }
  uint16_t host_tcp_port() const { return server_->tcp_port(); }
  bool device_open() const { return device_stream_ != nullptr; }
  uint32_t baud() const { return baud_; }
  const TapStats& stats() const { return stats_; }
  const session::SessionWriter* writer() const { return writer_.get(); }

 private:
  class Forwarder;
  class Recorder;
  void OpenDevice();
  void DeviceLost(const std::string& why);
  void ReadDevice();
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
  wire::Bytes pending_;   // host bytes waiting for the device's write
  wire::Bytes in_write_;  // the write in flight
  bool writing_ = false;
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
