// AVR firmware under libsimavr 1.6 as a conformance target on the firmware's clock
// (ARCHITECTURE "conformance", "One clock"; FACTS "simavr (Debian 1.6)").
#include "conformance/targets/simavr_target.h"

#include "conformance/targets/avr_elf.h"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

extern "C" {
#include "avr_ioport.h"
#include "avr_uart.h"
#include "sim_avr.h"
#include "sim_elf.h"
#include "sim_io.h"
#include "sim_irq.h"
#include "sim_regbit.h"
}

// libsimavr 1.6 never frees a core's IRQs (avr_terminate leaves them; a bare
// avr_make_mcu_by_name + avr_init + avr_terminate leaks the same): not this
// code's leak. LeakSanitizer reads this hook in sanitized builds of every
// program using the target (mococheck, the tests); elsewhere it is unused.
extern "C" const char* __lsan_default_suppressions() { return "leak:libsimavr.so\n"; }

namespace moco::conformance {
namespace {

constexpr const char* kDefaultMcu = "atmega328p";
constexpr uint32_t kDefaultFrequencyHz = 16'000'000;
constexpr uint64_t kNsPerSecond = 1'000'000'000;

// simavr logs through one process-wide function. Nothing reaches stdout or stderr;
// errors logged while a core is built are kept for the error message.
thread_local std::string* log_capture = nullptr;

// Set while a core runs (Receive): simavr reports an illegal instruction (and
// goes on as if it were a NOP) and an access outside the data memory (and
// stops the core) only through its logger. The first such error is kept.
thread_local std::string* core_error_seen = nullptr;

void QuietLogger(avr_t* /*avr*/, const int level, const char* format, va_list ap) {
  if (level > LOG_ERROR || (log_capture == nullptr && core_error_seen == nullptr)) return;
  char text[512];
  std::vsnprintf(text, sizeof text, format, ap);
  std::string line(text);
  // simavr colours its errors (ANSI escapes) and starts them with "CORE: *** ".
  for (size_t esc; (esc = line.find('\x1b')) != std::string::npos;) {
    const size_t end = line.find('m', esc);
    line.erase(esc, end == std::string::npos ? std::string::npos : end - esc + 1);
  }
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) {
    line.pop_back();
  }
  if (core_error_seen != nullptr) {
    if (core_error_seen->empty() && line.find("Invalid") != std::string::npos) {
      const size_t at = line.find("*** ");
      *core_error_seen = at == std::string::npos ? line : line.substr(at + 4);
    }
    return;
  }
  if (line.empty()) return;
  if (!log_capture->empty()) *log_capture += "; ";
  *log_capture += line;
}

// Keeps simulated time virtual: simavr's own sleep callback would usleep() for
// the time the firmware sleeps.
void NoHostSleep(avr_t* /*avr*/, avr_cycle_count_t /*how_long*/) {}

void FreeFirmware(elf_firmware_t& fw) {
  std::free(fw.flash);
  std::free(fw.eeprom);
  std::free(fw.fuse);
  std::free(fw.lockbits);
#if ELF_SYMBOLS
  if (fw.symbol != nullptr) {
    for (uint32_t i = 0; i < fw.symbolcount; ++i) std::free(fw.symbol[i]);
    std::free(fw.symbol);
  }
#endif
  fw.flash = fw.eeprom = fw.fuse = fw.lockbits = nullptr;
}

// simavr's USART0 module: the avr_io_t that hands out its IRQs is the first member
// of its avr_uart_t.
avr_uart_t* FindUart0(avr_t* avr) {
  for (avr_io_t* io = avr->io_port; io != nullptr; io = io->next) {
    if (io->irq_ioctl_get == AVR_IOCTL_UART_GETIRQ('0') && io->kind != nullptr &&
        std::strcmp(io->kind, "uart") == 0) {
      return reinterpret_cast<avr_uart_t*>(io);
    }
  }
  return nullptr;
}

}  // namespace

SimavrTarget::SimavrTarget(SimavrSpec spec, Options options)
    : spec_(std::move(spec)), options_(options) {}

SimavrTarget::~SimavrTarget() { Teardown(); }

std::string SimavrTarget::Name() const {
  std::string name = "simavr:" + spec_.elf_path;
  if (!mcu_.empty()) name += " @" + mcu_ + " " + std::to_string(frequency_hz_) + " Hz";
  if (!stopped_.empty()) name += " (firmware stopped: " + stopped_ + ")";
  return name;
}

std::optional<std::string> SimavrTarget::Open() {
  Teardown();
  unmodelled_.clear();
  // A stripped or odd symbol table only costs the reports their function names
  // (a path that is no regular file is refused by Build()).
  symbols_ = AvrSymbols::Read(spec_.elf_path, nullptr);
  return Build();
}

bool SimavrTarget::WatchFirmwareFaults() {
  watch_faults_ = true;
  return true;
}

void SimavrTarget::Restart() {
  if (auto err = Build()) stopped_ = *err;
}

void SimavrTarget::Teardown() {
  if (avr_ == nullptr) return;
  if (uart_ != nullptr) {
    const uint32_t ctl = AVR_IOCTL_UART_GETIRQ('0');
    avr_irq_unregister_notify(avr_io_getirq(avr_, ctl, UART_IRQ_OUTPUT), &OnOutput, this);
    avr_irq_unregister_notify(avr_io_getirq(avr_, ctl, UART_IRQ_OUT_XON), &OnXon, this);
    avr_irq_unregister_notify(avr_io_getirq(avr_, ctl, UART_IRQ_OUT_XOFF), &OnXoff, this);
  }
  for (const auto& hook : pin_hooks_) {
    avr_irq_unregister_notify(hook->irq, &OnPin, hook.get());
  }
  pin_hooks_.clear();
  if (timers_ != nullptr) {
    for (const std::string& note : timers_->Unmodelled()) {
      if (std::find(unmodelled_.begin(), unmodelled_.end(), note) == unmodelled_.end()) {
        unmodelled_.push_back(note);
      }
    }
    timers_.reset();
  }
  // simavr 1.6's avr_terminate() leaves the core's IRQs allocated (a few KB per core).
  avr_terminate(avr_);
  std::free(avr_);
  avr_ = nullptr;
  uart_ = nullptr;
  uart_input_ = nullptr;
}

std::optional<std::string> SimavrTarget::Build() {
  Teardown();
  stopped_.clear();
  stop_kind_ = FirmwareFaultKind::kCrash;
  stop_backtrace_.clear();
  core_error_.clear();
  if (watch_faults_) {
    faults_ = std::make_unique<AvrFaultWatch>(symbols_);
  } else {
    faults_.reset();
  }
  to_device_.clear();
  from_device_.clear();
  pacer_armed_ = false;
  xoff_ = false;
  rx_line_free_cycle_ = tx_line_free_cycle_ = 0;
  wake_cycle_ = 0;
  previous_pc_id_ = 0;

  std::error_code ec;
  if (!std::filesystem::exists(spec_.elf_path, ec)) {
    return "firmware ELF \"" + spec_.elf_path +
           "\" not found; give the path of an AVR ELF built with avr-gcc, e.g. "
           "simavr:build/dev/fixtures/firmware/dfmoco_avr/dfmoco.elf";
  }

  if (const std::string problem = CheckAvrElf(spec_.elf_path); !problem.empty()) {
    return "cannot read firmware ELF \"" + spec_.elf_path + "\": " + problem +
           "; give an AVR ELF linked by avr-gcc (not a .hex file)";
  }

  avr_global_logger_set(&QuietLogger);
  std::string log;
  log_capture = &log;
  struct Uncapture {
    ~Uncapture() { log_capture = nullptr; }
  } uncapture;

  elf_firmware_t fw;
  std::memset(&fw, 0, sizeof fw);
  if (elf_read_firmware(spec_.elf_path.c_str(), &fw) != 0 || fw.flash == nullptr ||
      fw.flashsize == 0) {
    FreeFirmware(fw);
    return "cannot read firmware ELF \"" + spec_.elf_path + "\"" +
           (log.empty() ? std::string() : " (" + log + ")") +
           "; give an AVR ELF linked by avr-gcc (not a .hex file)";
  }

  const std::string elf_mcu(fw.mmcu, std::find(fw.mmcu, fw.mmcu + sizeof fw.mmcu, '\0'));
  if (!spec_.mcu.empty() && !elf_mcu.empty() && spec_.mcu != elf_mcu) {
    FreeFirmware(fw);
    return "\"" + spec_.elf_path + "\" names its MCU \"" + elf_mcu +
           "\" in its .mmcu section but @" + spec_.mcu + " was given; drop the @MCU or give @" +
           elf_mcu;
  }
  mcu_ = !spec_.mcu.empty() ? spec_.mcu : (!elf_mcu.empty() ? elf_mcu : kDefaultMcu);
  frequency_hz_ = spec_.frequency_hz != 0
                      ? spec_.frequency_hz
                      : (fw.frequency != 0 ? fw.frequency : kDefaultFrequencyHz);

  avr_ = avr_make_mcu_by_name(mcu_.c_str());
  if (avr_ == nullptr) {
    FreeFirmware(fw);
    const std::string mcu = mcu_;
    mcu_.clear();
    return "simavr does not know the MCU \"" + mcu +
           "\"; give one it models, e.g. @atmega328p (Uno) or @atmega2560 (Mega)";
  }
  avr_init(avr_);
  // simavr 1.6 logs a read or write past the end of the data memory, marks the
  // core crashed, and still accesses avr->data at that address, past the
  // ramend + 1 bytes it allocated. A buffer for every 16-bit data address
  // keeps such an access in memory the core owns (avr_terminate frees it);
  // the run then stops on the logged error.
  if (avr_->ramend < 0xFFFF) {
    auto* wide = static_cast<uint8_t*>(std::calloc(0x10000, 1));
    if (wide != nullptr) {
      std::memcpy(wide, avr_->data, size_t{avr_->ramend} + 1);
      std::free(avr_->data);
      avr_->data = wide;
    }
  }
  avr_->log = LOG_ERROR;
  avr_->sleep = &NoHostSleep;
  std::snprintf(fw.mmcu, sizeof fw.mmcu, "%s", mcu_.c_str());
  fw.frequency = frequency_hz_;
  avr_load_firmware(avr_, &fw);
  // SRAM starts after the I/O registers; .data and .bss come first in it.
  data_end_ = static_cast<uint32_t>(avr_->ioend) + 1 + fw.datasize + fw.bsssize;
  // The program image: the code, then .data's initial values; past it the
  // flash is erased (0xFFFF), which simavr would run as instructions.
  code_end_ = fw.flashbase + fw.flashsize;
  code_map_.Prepare(avr_, code_end_);
  FreeFirmware(fw);
  avr_->frequency = frequency_hz_;
  if (options_.timer_model) timers_ = std::make_unique<AvrTimers>(avr_);

  uart_ = FindUart0(avr_);
  if (uart_ == nullptr) {
    const std::string mcu = mcu_;
    Teardown();
    return "the MCU \"" + mcu +
           "\" has no USART0 in simavr; give an MCU with one, e.g. @atmega328p";
  }
  uint32_t flags = 0;  // no console echo, no usleep() while the firmware polls UCSR0A
  avr_ioctl(avr_, AVR_IOCTL_UART_SET_FLAGS('0'), &flags);
  const uint32_t ctl = AVR_IOCTL_UART_GETIRQ('0');
  uart_input_ = avr_io_getirq(avr_, ctl, UART_IRQ_INPUT);
  avr_irq_register_notify(avr_io_getirq(avr_, ctl, UART_IRQ_OUTPUT), &OnOutput, this);
  avr_irq_register_notify(avr_io_getirq(avr_, ctl, UART_IRQ_OUT_XON), &OnXon, this);
  avr_irq_register_notify(avr_io_getirq(avr_, ctl, UART_IRQ_OUT_XOFF), &OnXoff, this);
  txen_ = avr_regbit_get(avr_, uart_->txen) != 0;
  if (options_.udre_fix) {
    // Added after the UART's own handler for this register, so it runs second.
    avr_register_io_write(avr_, uart_->txen.reg, &OnControlWrite, this);
  }
  if (watching_) {
    trace_ = PinTrace::For(board_);
    trace_.frequency_hz = frequency_hz_;
    trace_edges_ = 0;
    timed_.assign(trace_.signals.size(), 0);
    for (size_t i = 0; i < trace_.signals.size(); ++i) {
      const PinRef pin = trace_.signals[i].pin;
      if (pin.numbered()) {
        Teardown();
        return "board \"" + board_.name + "\": " + trace_.signals[i].name + " is pin " +
               pin.Name() +
               ", a numbered pin; a simavr: target watches AVR port pins: name it "
               "by its port and bit (e.g. \"PD4\")";
      }
      avr_irq_t* irq = avr_io_getirq(avr_, AVR_IOCTL_IOPORT_GETIRQ(pin.port), pin.bit);
      if (irq == nullptr) {
        const std::string mcu = mcu_;
        Teardown();
        return "board \"" + board_.name + "\": " + trace_.signals[i].name + " is on " + pin.Name() +
               ", but the MCU \"" + mcu + "\" has no port " + pin.port +
               "; fix the board profile or give the board's MCU (@MCU)";
      }
      pin_hooks_.push_back(std::make_unique<PinHook>(PinHook{this, static_cast<int>(i), irq}));
      avr_irq_register_notify(irq, &OnPin, pin_hooks_.back().get());
    }
  }
  return std::nullopt;
}

std::optional<std::string> SimavrTarget::WatchPins(const Board& board) {
  if (avr_ != nullptr) return "pins must be chosen before the firmware starts";
  board_ = board;
  watching_ = true;
  return std::nullopt;
}

// A PORTx bit changed: the edge's time is the cycle of the instruction writing it.
void SimavrTarget::OnPin(avr_irq_t* /*irq*/, uint32_t value, void* param) {
  auto* hook = static_cast<PinHook*>(param);
  SimavrTarget* self = hook->self;
  PinSignal& s = self->trace_.signals[static_cast<size_t>(hook->signal)];
  const bool level = (value & 1) != 0;
  const bool last = s.edges.empty() ? s.initial : s.edges.back().level;
  if (level == last) return;
  const uint64_t c = self->avr_->cycle;
  if (self->trace_edges_ >= kMaxPinEdges) {
    self->trace_.complete_until_ns = std::min(self->trace_.complete_until_ns, self->CyclesToNs(c));
    return;
  }
  ++self->trace_edges_;
  s.edges.push_back(PinEdge{0, c, level});  // t_ns: filled in by Pins()
}

TimeNs SimavrTarget::CyclesToNs(uint64_t c) const {
  return static_cast<TimeNs>((c / frequency_hz_) * kNsPerSecond +
                             (c % frequency_hz_) * kNsPerSecond / frequency_hz_);
}

const PinTrace* SimavrTarget::Pins() const {
  if (!watching_) return nullptr;
  for (size_t i = 0; i < trace_.signals.size() && i < timed_.size(); ++i) {
    std::vector<PinEdge>& edges = trace_.signals[i].edges;
    for (size_t k = timed_[i]; k < edges.size(); ++k) edges[k].t_ns = CyclesToNs(edges[k].cycle);
    timed_[i] = edges.size();
  }
  return &trace_;
}

std::vector<std::string> SimavrTarget::Unmodelled() const {
  std::vector<std::string> notes = unmodelled_;
  if (timers_ != nullptr) {
    for (const std::string& note : timers_->Unmodelled()) {
      if (std::find(notes.begin(), notes.end(), note) == notes.end()) notes.push_back(note);
    }
  }
  return notes;
}

std::vector<std::string> SimavrTarget::Caveats() const {
  std::vector<std::string> caveats = Unmodelled();
  if (timers_ != nullptr) {
    for (std::string& silent : timers_->SilentInterrupts()) caveats.push_back(std::move(silent));
  }
  return caveats;
}

uint64_t SimavrTarget::cycles() const { return avr_ == nullptr ? 0 : avr_->cycle; }

TimeNs SimavrTarget::Now() const {
  if (avr_ == nullptr || frequency_hz_ == 0) return 0;
  const uint64_t c = avr_->cycle;
  return static_cast<TimeNs>((c / frequency_hz_) * kNsPerSecond +
                             (c % frequency_hz_) * kNsPerSecond / frequency_hz_);
}

TimeNs SimavrTarget::SentBy() const {
  if (avr_ == nullptr) return Now();
  const uint64_t line_free = std::max<uint64_t>(avr_->cycle, rx_line_free_cycle_);
  return CyclesToNs(line_free + to_device_.size() * FrameCycles());
}

uint64_t SimavrTarget::NsToCycles(TimeNs ns) const {
  if (ns <= 0) return 0;
  const auto u = static_cast<uint64_t>(ns);
  // Rounded up: the first cycle at or after `ns`.
  return (u / kNsPerSecond) * frequency_hz_ +
         ((u % kNsPerSecond) * frequency_hz_ + kNsPerSecond - 1) / kNsPerSecond;
}

uint64_t SimavrTarget::FrameCycles() const {
  if (avr_ == nullptr) return 0;
  const uint64_t ubrr = avr_regbit_get(avr_, uart_->ubrrl) |
                        (static_cast<uint64_t>(avr_regbit_get(avr_, uart_->ubrrh)) << 8);
  const uint64_t cycles_per_bit = (ubrr + 1) * (avr_regbit_get(avr_, uart_->u2x) ? 8 : 16);
  // UCSZ 0..3 are 5..8 data bits, 7 is 9 bits (4..6 are reserved: taken as 8).
  const unsigned ucsz = avr_regbit_get(avr_, uart_->ucsz) |
                        static_cast<unsigned>(avr_regbit_get(avr_, uart_->ucsz2) << 2);
  const uint64_t data_bits = ucsz <= 3 ? 5 + ucsz : (ucsz == 7 ? 9 : 8);
  // UPMn1..0 (parity mode) are bits 5..4 of UCSRnC on the megaAVRs simavr models.
  const uint64_t parity_bits = (avr_->data[uart_->r_ucsrc] & 0x30) != 0 ? 1 : 0;
  const uint64_t stop_bits = 1 + avr_regbit_get(avr_, uart_->usbs);
  return cycles_per_bit * (1 + data_bits + parity_bits + stop_bits);
}

std::string SimavrTarget::At() const {
  char when[64];
  std::snprintf(when, sizeof when, " at %.6f s, pc 0x%04x", static_cast<double>(Now()) / 1e9,
                static_cast<unsigned>(avr_->pc));
  return when;
}

bool SimavrTarget::StackCollided() {
  // SP is the next free byte: the last push wrote at SP + 1.
  const uint32_t sp = avr_stack::StackPointer(avr_);
  if (sp + 1 >= data_end_) return false;
  char what[120];
  std::snprintf(what, sizeof what,
                "the stack ran into .data/.bss (SP 0x%04x, below their end 0x%04x)", sp, data_end_);
  Stop(FirmwareFaultKind::kStackOverflow, what);
  return true;
}

bool SimavrTarget::LeftTheProgram() {
  if (avr_->pc < code_end_) return false;
  char what[120];
  std::snprintf(what, sizeof what,
                "the program counter left the program (its image ends at 0x%04x)", code_end_);
  Stop(FirmwareFaultKind::kCrash, what);
  return true;
}

bool SimavrTarget::CheckAlive() {
  if (avr_ == nullptr) return false;
  if (!stopped_.empty()) return false;
  const int state = avr_->state;
  if (state == cpu_Running || state == cpu_Sleeping) return true;
  if (state == cpu_Done) {
    Stop(FirmwareFaultKind::kCrash, "the core halted (it sleeps with interrupts off)");
  } else if (state == cpu_Crashed) {
    Stop(FirmwareFaultKind::kCrash, "the core crashed");
  } else {
    Stop(FirmwareFaultKind::kCrash,
         "the core does not run (simavr state " + std::to_string(state) + ")");
  }
  return false;
}

bool SimavrTarget::Send(wire::ByteView bytes) {
  if (!CheckAlive()) return false;
  to_device_.insert(to_device_.end(), bytes.begin(), bytes.end());
  StartPacer();
  return true;
}

void SimavrTarget::StartPacer() {
  if (pacer_armed_ || to_device_.empty()) return;
  const uint64_t now = avr_->cycle;
  const uint64_t start = std::max(now, rx_line_free_cycle_);
  pacer_armed_ = true;
  avr_cycle_timer_register(avr_, start - now, &PacerTick, this);
}

// Starts the next host byte on the line: it enters the receiver at its start bit.
uint64_t SimavrTarget::PacerTick(avr_t* /*avr*/, uint64_t when, void* param) {
  auto* self = static_cast<SimavrTarget*>(param);
  const uint64_t frame = self->FrameCycles();
  if (self->to_device_.empty()) {
    self->pacer_armed_ = false;
    return 0;
  }
  if (self->xoff_) return when + frame;  // simavr's FIFO is full: hold the line
  const uint8_t byte = self->to_device_.front();
  self->to_device_.pop_front();
  self->rx_line_free_cycle_ = when + frame;
  avr_raise_irq(self->uart_input_, byte);
  if (self->to_device_.empty()) {
    self->pacer_armed_ = false;
    return 0;
  }
  return when + frame;
}

uint64_t SimavrTarget::WakeTick(avr_t* /*avr*/, uint64_t /*when*/, void* param) {
  static_cast<SimavrTarget*>(param)->wake_cycle_ = 0;
  return 0;
}

// A sleeping core jumps to its next timer; this one makes it stop where Receive() must.
void SimavrTarget::ArmWake(uint64_t cycle) {
  if (wake_cycle_ == cycle) return;
  avr_cycle_timer_cancel(avr_, &WakeTick, this);
  wake_cycle_ = 0;
  if (cycle <= avr_->cycle) return;
  wake_cycle_ = cycle;
  avr_cycle_timer_register(avr_, cycle - avr_->cycle, &WakeTick, this);
}

void SimavrTarget::OnOutput(avr_irq_t* /*irq*/, uint32_t value, void* param) {
  auto* self = static_cast<SimavrTarget*>(param);
  const uint64_t start = std::max(self->avr_->cycle, self->tx_line_free_cycle_);
  const uint64_t ready = start + self->FrameCycles();
  self->tx_line_free_cycle_ = ready;
  self->from_device_.push_back(OutByte{static_cast<uint8_t>(value), ready});
}

void SimavrTarget::OnXon(avr_irq_t* /*irq*/, uint32_t value, void* param) {
  if (value != 0) static_cast<SimavrTarget*>(param)->xoff_ = false;
}

void SimavrTarget::OnXoff(avr_irq_t* /*irq*/, uint32_t value, void* param) {
  if (value != 0) static_cast<SimavrTarget*>(param)->xoff_ = true;
}

// UCSR0B written (after simavr's UART handler): TXEN0 0 -> 1 empties the transmit
// buffer on the hardware, so UDRE0 is raised (and its interrupt, when enabled).
void SimavrTarget::OnControlWrite(avr_t* avr, uint16_t addr, uint8_t value, void* param) {
  auto* self = static_cast<SimavrTarget*>(param);
  const avr_regbit_t txen = self->uart_->txen;
  if (addr != txen.reg) return;
  const bool now_on = ((value >> txen.bit) & txen.mask) != 0;
  if (now_on && !self->txen_) avr_raise_interrupt(avr, &self->uart_->udrc);
  self->txen_ = now_on;
}

bool SimavrTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  if (avr_ == nullptr) return false;
  const uint64_t deadline = NsToCycles(deadline_ns);
  core_error_seen = &core_error_;
  struct Unwatch {
    ~Unwatch() { core_error_seen = nullptr; }
  } unwatch;
  bool alive = true;
  uint32_t polls = 0;
  bool stop_requested = false;
  for (;;) {
    bool delivered = false;
    while (!from_device_.empty() && from_device_.front().ready_cycle <= avr_->cycle) {
      out.push_back(from_device_.front().value);
      from_device_.pop_front();
      delivered = true;
    }
    if (delivered) break;
    if (!(alive = CheckAlive())) {
      // Bytes already in the transmitter still reach the wire.
      for (const OutByte& b : from_device_) out.push_back(b.value);
      from_device_.clear();
      break;
    }
    if (avr_->cycle >= deadline) break;
    uint64_t stop = deadline;
    if (!from_device_.empty()) stop = std::min(stop, from_device_.front().ready_cycle);
    ArmWake(stop);
    const size_t written = from_device_.size();
    int stalls = 0;  // avr_run() calls in a row that left the cycle count alone
    while (avr_->cycle < stop && from_device_.size() == written) {
      // A stop request ends a long run of the core (a firmware spinning for
      // seconds of its time) as it ends every other wait.
      if ((++polls & 0xFFF) == 0 && StopRequested() != 0) {
        stop_requested = true;
        break;
      }
      const uint64_t before = avr_->cycle;
      const uint32_t pc_before = static_cast<uint32_t>(avr_->pc);
      const uint8_t serving = avr_->interrupts.running_ptr;
      const bool was_running = avr_->state == cpu_Running;
      if (faults_ != nullptr && StopAt(faults_->Before(avr_))) break;
      const int state = avr_run(avr_);
      if (coverage_ != nullptr) CountEdge();
      if (instruction_map_ != nullptr && was_running) {
        code_map_.Record(instruction_map_, pc_before, avr_, avr_->interrupts.running_ptr > serving);
      }
      if (faults_ != nullptr && StopAt(faults_->After(avr_))) break;
      if (!core_error_.empty()) {
        StopForCoreError(pc_before);
        break;
      }
      if (state != cpu_Running && state != cpu_Sleeping) break;
      // Each checked inline first: this runs after every instruction.
      if ((avr_stack::StackPointer(avr_) + 1 < data_end_ && StackCollided()) ||
          (avr_->pc >= code_end_ && LeftTheProgram())) {
        break;
      }
      // A call may wake the core without a cycle passing; a thousand in a row is a hang.
      stalls = avr_->cycle == before ? stalls + 1 : 0;
      if (stalls > 1000) {
        Stop(FirmwareFaultKind::kCrash,
             "the core makes no progress (simavr state " + std::to_string(state) + ")");
        break;
      }
    }
    if (stop_requested) break;
  }
  ArmWake(0);
  return alive && !stop_requested;
}

std::optional<std::string> SimavrTarget::FirmwareStopped() const {
  if (stopped_.empty()) return std::nullopt;
  return stopped_;
}

std::optional<FirmwareFault> SimavrTarget::FirmwareFaulted() const {
  if (stopped_.empty()) return std::nullopt;
  return FirmwareFault{stop_kind_, stopped_, stop_backtrace_};
}

std::vector<std::string> SimavrTarget::FirmwareBacktrace() const {
  if (avr_ == nullptr) return {};
  const uint32_t pc = static_cast<uint32_t>(avr_->pc);
  if (faults_ != nullptr) return faults_->Backtrace(pc);
  return {symbols_.Describe(pc)};
}

void SimavrTarget::StopForCoreError(uint32_t pc_before) {
  char what[200];
  if (core_error_.find("Invalid Opcode") != std::string::npos) {
    // simavr has already moved past it: the instruction was at the PC before.
    std::snprintf(what, sizeof what, "an illegal instruction (0x%04x) at %s",
                  static_cast<unsigned>(avr_->flash[pc_before] | (avr_->flash[pc_before + 1] << 8)),
                  symbols_.Describe(pc_before).c_str());
  } else {
    // simavr stops the core at a read or write outside the data memory.
    std::snprintf(what, sizeof what, "an access outside the data memory at %s (simavr: %s)",
                  symbols_.Describe(pc_before).c_str(), core_error_.c_str());
  }
  Stop(FirmwareFaultKind::kCrash, what);
}

void SimavrTarget::Stop(FirmwareFaultKind kind, const std::string& what) {
  if (!stopped_.empty()) return;  // the first fault stands
  stop_kind_ = kind;
  stop_backtrace_ = FirmwareBacktrace();
  stopped_ = what + At();
}

bool SimavrTarget::StopAt(std::optional<AvrFault> fault) {
  if (!fault) return false;
  FirmwareFaultKind kind = FirmwareFaultKind::kStackSmash;
  if (fault->kind == AvrFaultKind::kDivisionByZero) kind = FirmwareFaultKind::kDivisionByZero;
  if (fault->kind == AvrFaultKind::kReset) kind = FirmwareFaultKind::kReset;
  Stop(kind, fault->what);
  return true;
}

bool SimavrTarget::SetCoverageMap(uint8_t* map, size_t size) {
  if (map != nullptr && (size == 0 || (size & (size - 1)) != 0)) return false;
  coverage_ = map;
  coverage_mask_ = map == nullptr ? 0 : size - 1;
  previous_pc_id_ = 0;
  return true;
}

size_t SimavrTarget::InstructionMapBytes() const { return code_map_.bytes(); }

bool SimavrTarget::SetInstructionMap(uint8_t* map, size_t size) {
  if (map != nullptr && size < code_map_.bytes()) return false;
  instruction_map_ = map;
  return true;
}

std::optional<CodeCoverage> SimavrTarget::CodeCoverageOf(std::span<const uint8_t> map) const {
  if (code_map_.bytes() == 0) return std::nullopt;
  return code_map_.Summarise(map, symbols_);
}

void SimavrTarget::CountEdge() {
  // A PC's id: its word address, mixed so that nearby addresses spread over
  // the map (Fibonacci hashing); the edge is the id xor the previous id
  // shifted, so A->B and B->A differ.
  const uint32_t id = (static_cast<uint32_t>(avr_->pc) >> 1) * 2654435761u;
  const uint32_t id16 = id >> 16;
  uint8_t& slot = coverage_[(id16 ^ previous_pc_id_) & coverage_mask_];
  if (slot != 255) ++slot;
  previous_pc_id_ = id16 >> 1;
}

}  // namespace moco::conformance
