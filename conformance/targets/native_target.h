// Firmware built for the host Arduino core (conformance/arduino, docs/firmware-
// ci.md) as a conformance target: the executable runs as a child process on
// its own simulated clock, which moves only as far as this target grants it
// over the link (conformance/arduino/link.h). Runs are deterministic: the same
// traffic gives the same bytes at the same simulated times.
#ifndef MOCO_CONFORMANCE_TARGETS_NATIVE_TARGET_H_
#define MOCO_CONFORMANCE_TARGETS_NATIVE_TARGET_H_

#include <sys/types.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "conformance/arduino/link.h"
#include "conformance/targets/target.h"

namespace moco::conformance {

// The address of a "native:" target: "PATH[@PORT]", PORT the sketch's serial
// port the protocol is spoken on: serial (default), serial1, serial2 or
// bluetooth (an ESP32's BluetoothSerial).
struct NativeSpec {
  std::string path;
  arduino::link::Port port = arduino::link::Port::kSerial;
  // How long a slice of simulated time may take in wall time before the
  // firmware is taken to be stuck (NativeTarget::kStallWallSeconds).
  int stall_wall_seconds = 20;
};
std::variant<NativeSpec, std::string> ParseNativeAddress(std::string_view address);

// Line model: the host's bytes enter the port's line when sent and reach the
// sketch's receive buffer one frame apart at the baud the sketch gave begin()
// (a USB or Bluetooth port: at once, and held back while its buffer is full);
// a full UART buffer drops them, as the hardware does. A byte the sketch writes
// is handed out when its stop bit has been sent.
//
// Pin model (WatchPins): digitalWrite() and the direct port writes the board's
// port map names, each an edge at its simulated time. Pins named by port and
// bit ("PD4") are found through the board's port map; numbered ones ("GPIO26")
// directly.
//
// What stops the firmware: the process ending (a crash, a signal, an exit),
// the core refusing an API, or no grant answered within the spec's
// stall_wall_seconds of wall time (a loop that calls nothing of the core never
// lets time move).
class NativeTarget final : public Target {
 public:
  explicit NativeTarget(NativeSpec spec);
  ~NativeTarget() override;
  NativeTarget(const NativeTarget&) = delete;
  NativeTarget& operator=(const NativeTarget&) = delete;

  std::string Name() const override;
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  // Starts the executable. Errors name a missing, non-regular or
  // non-executable file, and a program that is not built for this target.
  std::optional<std::string> Open() override;
  // Ends the process and starts it again: time 0, empty buffers.
  void Restart() override;
  TimeNs Now() const override { return now_ns_; }
  bool Send(wire::ByteView bytes) override;
  TimeNs SentBy() const override;
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override;

  std::optional<std::string> FirmwareStopped() const override;
  std::optional<FirmwareFault> FirmwareFaulted() const override;
  std::optional<std::string> WatchPins(const Board& board) override;
  const PinTrace* Pins() const override { return watching_ ? &trace_ : nullptr; }
  // What the sketch used that the core does not model, and the one thing the
  // native target never reproduces: the time the sketch's own code takes.
  std::vector<std::string> Caveats() const override;

  // The board the firmware was built for (after Open()).
  const std::string& board() const { return board_name_; }

  static constexpr size_t kMaxPinEdges = size_t{8} << 20;
  // A grant is cut into slices of this much simulated time, each answered
  // within NativeSpec::stall_wall_seconds.
  static constexpr TimeNs kSliceNs = 100 * sim::kNsPerMs;

 private:
  std::optional<std::string> Start();
  void Teardown();
  // Reads packets until a yield; false when the firmware stopped.
  bool AwaitYield(wire::Bytes* out);
  // The firmware's next packet into rx_packet_, its length in `size`.
  bool ReadPacket(size_t& size);
  void Stop(std::string what);
  // Why the process ended (waits for it).
  std::string Ended();
  void AddEdges(arduino::link::Reader& r);

  NativeSpec spec_;
  pid_t pid_ = -1;
  int fd_ = -1;
  TimeNs now_ns_ = 0;
  TimeNs line_free_ns_ = 0;
  TimeNs frame_ns_ = 0;
  wire::Bytes pending_;  // sent, not yet handed to the firmware
  // Packet buffers, reused: a grant and its answer go back and forth for
  // every byte the firmware sends.
  std::vector<uint8_t> rx_packet_, tx_packet_;
  std::string stopped_;
  FirmwareFaultKind stop_kind_ = FirmwareFaultKind::kCrash;
  std::string board_name_;
  std::map<std::pair<char, uint8_t>, int> port_map_;  // (port, bit) -> pin
  std::vector<std::string> notes_;
  uint64_t dropped_ = 0;
  bool watching_ = false;
  Board watched_board_;
  PinTrace trace_;
  std::multimap<int, int> signal_of_pin_;  // pin -> index into trace_.signals
  size_t trace_edges_ = 0;
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_NATIVE_TARGET_H_
