// Real AVR firmware as a conformance target: an ELF run by libsimavr (Debian 1.6)
// on the firmware's own clock (ARCHITECTURE "conformance", "One clock"; FACTS
// "simavr (Debian 1.6)"). Host bytes reach USART0's receiver at the baud the
// firmware configured; device bytes are handed out when their stop bit is sent.
#ifndef MOCO_CONFORMANCE_TARGETS_SIMAVR_TARGET_H_
#define MOCO_CONFORMANCE_TARGETS_SIMAVR_TARGET_H_

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "conformance/targets/avr_code_map.h"
#include "conformance/targets/avr_elf.h"
#include "conformance/targets/avr_faults.h"
#include "conformance/targets/avr_timers.h"
#include "conformance/targets/target.h"

struct avr_t;
struct avr_irq_t;
struct avr_uart_t;

namespace moco::conformance {

// Runs `spec.elf_path` in a simulated AVR. Time is the firmware's: cycles / F_CPU.
// The MCU and clock are the spec's when given, else those the ELF's .mmcu section
// names, else atmega328p at 16 MHz.
//
// Line model (USART0; data, parity and stop bits as UCSR0B/UCSR0C say):
//  - Host bytes queue up; one starts every frame time of the baud the firmware set
//    in UBRR0 and U2X0 (10 bit times for 8N1) and enters simavr's receiver at its
//    start bit; simavr raises RXC0 one frame later. While simavr's input FIFO
//    signals XOFF no byte is started. Bytes sent while the receiver is off are
//    lost, as on the wire.
//  - A byte the firmware writes to UDR0 is handed out by Receive() once it has
//    been shifted out: one frame after it started, and it starts when the
//    previous byte has finished.
//  - simavr 1.6 clears UDRE0 when TXEN0 is switched off but does not set it again
//    when TXEN0 is switched back on; firmware that writes UCSR0B = 0 first (the
//    Arduino core's init() does) and then polls UDRE0 would never transmit. A
//    write hook on UCSR0B raises UDRE0 when TXEN0 goes from 0 to 1, as the
//    hardware does (the transmit buffer is empty then).
//  - Firmware that stops (sleep with interrupts off, or a crash) ends the link:
//    Send() and Receive() return false and Name() says what happened. So do a
//    stack that grows into .data/.bss (SP below their end, from the ELF's
//    section sizes: the firmware has overwritten its own variables) and a
//    program counter past the program image (erased flash, after a bad jump).
// simavr's own console output is silenced; its error messages go into Open()'s
// error text.
//
// Pin model (WatchPins): every pin the board names is followed through simavr's
// I/O port IRQs (AVR_IOCTL_IOPORT_GETIRQ), which fire as the instruction writing
// PORTx executes; each level change is kept with avr->cycle, so an edge's time is
// exact to one CPU cycle and nothing polls. All levels start low (the reset
// state of PORTx). A case keeps at most kMaxPinEdges edges; later ones are
// dropped and PinTrace::complete_until_ns says from when.
//
// Timer model (Options::timer_model, on by default): simavr 1.6's timers run at
// wrong periods in several modes (FACTS "simavr"); AvrTimers (avr_timers.h)
// replaces them, and what it does not model is named by Unmodelled().
class SimavrTarget final : public Target {
 public:
  struct Options {
    // Test only: false leaves simavr's UDRE0 behaviour as it is.
    bool udre_fix = true;
    // Test only: false leaves simavr's own timer/counters in charge.
    bool timer_model = true;
  };

  explicit SimavrTarget(SimavrSpec spec) : SimavrTarget(std::move(spec), Options()) {}
  SimavrTarget(SimavrSpec spec, Options options);
  ~SimavrTarget() override;
  SimavrTarget(const SimavrTarget&) = delete;
  SimavrTarget& operator=(const SimavrTarget&) = delete;

  // "simavr:PATH @MCU HZ", plus "(firmware stopped: ...)" once the core has ended.
  std::string Name() const override;
  bool VirtualClock() const override { return true; }
  bool CanRestart() const override { return true; }
  // Loads the ELF into a fresh core at cycle 0. Errors name a missing or unreadable
  // ELF, an MCU simavr does not know, an MCU that contradicts the ELF's .mmcu
  // section, or an MCU without USART0.
  std::optional<std::string> Open() override;
  // Reloads the firmware into a fresh core (time 0, empty queues).
  void Restart() override;
  TimeNs Now() const override;
  bool Send(wire::ByteView bytes) override;
  // The host's line paced at the firmware's baud rate: the frame on the line,
  // then one frame per byte still queued.
  TimeNs SentBy() const override;
  // Runs the core until a device byte has been shifted out or Now() >= deadline_ns.
  bool Receive(TimeNs deadline_ns, wire::Bytes& out) override;

  // After Open(): the MCU and clock in use.
  const std::string& mcu() const { return mcu_; }
  uint32_t frequency_hz() const { return frequency_hz_; }
  // CPU cycles executed since Open() / Restart().
  uint64_t cycles() const;
  // Cycles one USART0 frame takes at the firmware's current settings.
  uint64_t FrameCycles() const;

  static constexpr size_t kMaxPinEdges = size_t{8} << 20;
  std::optional<std::string> WatchPins(const Board& board) override;
  // Edge times (t_ns) are filled in here, from their cycles, off the firmware's hot path.
  const PinTrace* Pins() const override;

  // Timer features the firmware used that the model does not reproduce, since
  // Open() (across restarts), one sentence each (AvrTimers::Unmodelled()).
  std::vector<std::string> Unmodelled() const;
  // Unmodelled(), then each timer interrupt enabled now that has never fired
  // since the last Open() / Restart(), with the reason.
  std::vector<std::string> Caveats() const override;

  // Also stops on an illegal instruction (simavr would run it as a NOP). With
  // WatchFirmwareFaults(), an AvrFaultWatch (avr_faults.h) checks every
  // instruction; backtraces name the ELF's functions.
  std::optional<std::string> FirmwareStopped() const override;
  std::optional<FirmwareFault> FirmwareFaulted() const override;
  bool WatchFirmwareFaults() override;
  std::vector<std::string> FirmwareBacktrace() const override;
  // Edges are (previous PC, PC) pairs of the instructions the core executes,
  // hashed into `map` as AFL does; an interrupt's entry is an edge too.
  bool SetCoverageMap(uint8_t* map, size_t size) override;
  // One byte per flash word of the image (AvrCodeMap).
  size_t InstructionMapBytes() const override;
  bool SetInstructionMap(uint8_t* map, size_t size) override;
  std::optional<CodeCoverage> CodeCoverageOf(std::span<const uint8_t> map) const override;

 private:
  struct OutByte {
    uint8_t value;
    uint64_t ready_cycle;  // its stop bit has been sent
  };

  std::optional<std::string> Build();
  void Teardown();
  bool CheckAlive();
  uint64_t NsToCycles(TimeNs ns) const;
  TimeNs CyclesToNs(uint64_t cycles) const;
  void StartPacer();
  void ArmWake(uint64_t cycle);
  void CountEdge();
  // " at T s, pc 0x...": where the firmware is now, for stopped_.
  std::string At() const;
  // Ends the firmware's run for `what` (the first call stands), with the time,
  // the PC and the backtrace.
  void Stop(FirmwareFaultKind kind, const std::string& what);
  // Stop()s for core_error_: the instruction at `pc_before` was illegal or
  // accessed no data memory.
  void StopForCoreError(uint32_t pc_before);
  // Stop()s for a fault the watch saw; whether there was one.
  bool StopAt(std::optional<AvrFault> fault);
  // Whether the stack has grown into .data/.bss; stops the firmware when so.
  bool StackCollided();
  // Whether the PC has run past the program image into erased flash; stops
  // the firmware when so.
  bool LeftTheProgram();

  static uint64_t PacerTick(avr_t* avr, uint64_t when, void* param);
  static uint64_t WakeTick(avr_t* avr, uint64_t when, void* param);
  static void OnOutput(avr_irq_t* irq, uint32_t value, void* param);
  static void OnXon(avr_irq_t* irq, uint32_t value, void* param);
  static void OnXoff(avr_irq_t* irq, uint32_t value, void* param);
  static void OnControlWrite(avr_t* avr, uint16_t addr, uint8_t value, void* param);
  static void OnPin(avr_irq_t* irq, uint32_t value, void* param);

  struct PinHook {
    SimavrTarget* self;
    int signal;  // index into trace_.signals
    avr_irq_t* irq;
  };

  SimavrSpec spec_;
  Options options_;
  std::string mcu_;
  uint32_t frequency_hz_ = 0;

  avr_t* avr_ = nullptr;
  avr_uart_t* uart_ = nullptr;
  avr_irq_t* uart_input_ = nullptr;
  bool txen_ = false;    // TXEN0 as last written
  std::string stopped_;  // why the core ended; empty while it runs
  FirmwareFaultKind stop_kind_ = FirmwareFaultKind::kCrash;
  std::vector<std::string> stop_backtrace_;
  std::string core_error_;  // simavr logged an illegal instruction or a bad access
  AvrSymbols symbols_;      // the ELF's code symbols (Open())
  bool watch_faults_ = false;
  std::unique_ptr<AvrFaultWatch> faults_;  // with watch_faults_, one per core
  std::deque<uint8_t> to_device_;          // host bytes not yet started
  bool pacer_armed_ = false;
  bool xoff_ = false;
  uint64_t rx_line_free_cycle_ = 0;  // the host's line is idle from here
  std::deque<OutByte> from_device_;  // written by the firmware, maybe still shifting
  uint64_t tx_line_free_cycle_ = 0;  // the device's line is idle from here
  uint64_t wake_cycle_ = 0;          // an armed WakeTick, 0 when none
  bool watching_ = false;
  Board board_;
  mutable PinTrace trace_;
  mutable std::vector<size_t> timed_;  // per signal: edges whose t_ns is filled in
  size_t trace_edges_ = 0;
  std::vector<std::unique_ptr<PinHook>> pin_hooks_;
  std::unique_ptr<AvrTimers> timers_;
  uint32_t data_end_ = 0;               // the first SRAM byte after .data and .bss
  uint32_t code_end_ = 0;               // the first flash byte after the program image
  uint8_t* coverage_ = nullptr;         // SetCoverageMap(); nullptr: not counted
  AvrCodeMap code_map_;                 // the image's instruction lengths (Build())
  uint8_t* instruction_map_ = nullptr;  // SetInstructionMap(); nullptr: not marked
  size_t coverage_mask_ = 0;
  uint32_t previous_pc_id_ = 0;          // the last PC's id, shifted (AFL's prev_loc)
  std::vector<std::string> unmodelled_;  // notes of cores already torn down
};

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_TARGETS_SIMAVR_TARGET_H_
