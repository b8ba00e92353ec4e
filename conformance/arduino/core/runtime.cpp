// The host Arduino core's simulated time (include/moco_core.h): the clock, the
// events that fall due in it (timer interrupts, serial bytes on the line) and
// the runner's grants of time over the link (link.h).
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <deque>
#include <set>
#include <string>
#include <vector>

#include "../link.h"
#include "moco_core.h"
#include "runtime_internal.h"

namespace moco::arduino {
namespace {

constexpr TimeNs kNever = INT64_MAX;

struct Timer {
  void (*isr)() = nullptr;
  bool running = false;
  bool pending = false;  // fell due while interrupts were off
  TimeNs started_ns = 0;
  TimeNs due_ns = kNever;
  TimeNs period_ns = 0;
};

struct ArrivingByte {
  TimeNs at_ns;
  uint8_t value;
};

struct SerialPort {
  bool begun = false;
  bool usb = false;  // not paced, never drops: the host waits instead
  uint32_t baud = 0;
  TimeNs frame_ns = 0;
  size_t rx_capacity = 64, tx_capacity = 64;
  std::deque<ArrivingByte> line;  // the host's bytes on their way in
  TimeNs line_free_ns = 0;
  std::deque<uint8_t> rx;
  std::deque<uint8_t> tx;  // waiting to be shifted out
  bool shifting = false;   // a byte is on the wire
  uint8_t shifting_value = 0;
  TimeNs shift_done_ns = kNever;
};

class Runtime {
 public:
  TimeNs now_ns = 0;
  TimeNs grant_ns = -1;  // time may run up to here (the first grant comes at start)
  TimeNs next_event_ns = 0;
  bool stop_at_output = false;
  bool irq_flag = true;  // cli()/sei()
  int critical = 0;      // portENTER_CRITICAL depth
  bool in_isr = false;
  std::vector<Timer> timers;
  SerialPort ports[4];
  int protocol_port = 0;
  std::vector<uint8_t> levels;
  std::vector<bool> watched;
  std::vector<uint8_t> out_packet, edge_packet;
  // The largest packet the runner sends (a run with the host's bytes).
  static constexpr size_t kMaxRunPacketBytes = 256 * 1024;
  std::vector<uint8_t> rx_packet;
  std::set<std::string> notes;
  std::vector<std::string> pending_notes;
  uint32_t dropped = 0;
  std::vector<uint8_t> eeprom;
  bool connected = false;

  Runtime() { timers.reserve(16); }

  bool InterruptsEnabled() const { return irq_flag && critical == 0 && !in_isr; }

  void Connect() {
    connected = true;
    if (getenv(link::kLinkEnv) == nullptr) {
      fprintf(stderr,
              "this program is firmware built for mococheck's native target; run it with\n"
              "  mococheck run --target native:PROGRAM --protocol dfmoco|dmc|stackshot\n");
      _exit(2);
    }
    const BoardSpec& b = TheBoard();
    levels.assign(static_cast<size_t>(b.pins), 0);
    watched.assign(static_cast<size_t>(b.pins), false);
    eeprom.assign(b.eeprom_bytes, 0xFF);
    for (int i = 0; i < 4; ++i) {
      SerialPort& p = ports[i];
      p.usb = i == 0 && b.serial_is_usb;
      p.rx_capacity = p.usb ? b.usb_buffer_bytes : b.uart_rx_buffer_bytes;
      p.tx_capacity = p.usb ? b.usb_buffer_bytes : b.uart_tx_buffer_bytes;
    }
    ports[0].begun = ports[0].usb;     // USB serial is up without begin()
    ports[kBluetoothPort].usb = true;  // the radio link: the host is paced by the stack
    std::vector<uint8_t> hello{static_cast<uint8_t>(link::Type::kHello)};
    link::Put(hello, link::kLinkVersion, 4);
    const std::string name = b.name;
    link::Put(hello, std::min<size_t>(name.size(), 255), 1);
    hello.insert(hello.end(), name.begin(), name.begin() + std::min<size_t>(name.size(), 255));
    link::Put(hello, b.port_map_size, 2);
    for (size_t i = 0; i < b.port_map_size; ++i) {
      link::Put(hello, b.port_map[i].pin, 2);
      link::Put(hello, static_cast<uint8_t>(b.port_map[i].port), 1);
      link::Put(hello, b.port_map[i].bit, 1);
    }
    SendPacket(hello);
    ReceiveAttach();
    CatchFaults();
  }

  // A fault signal becomes a kStopped naming it, at the time it happened:
  // the runner reports it as a finding (the kind, the time) rather than an
  // unexplained end of the process. Only async-signal-safe calls in the handler.
  static void OnFault(int signal_number) {
    char packet[96];
    packet[0] = static_cast<char>(link::Type::kStopped);
    packet[1] = static_cast<char>(signal_number == SIGFPE ? link::Fault::kDivisionByZero
                                                          : link::Fault::kCrash);
    const char* what = signal_number == SIGSEGV  ? "a bad memory access (SIGSEGV)"
                       : signal_number == SIGBUS ? "a bad memory access (SIGBUS)"
                       : signal_number == SIGILL ? "an illegal instruction (SIGILL)"
                       : signal_number == SIGFPE ? "a division by zero (SIGFPE)"
                                                 : "an abort (SIGABRT)";
    size_t n = 2;
    for (const char* c = "the sketch stopped at "; *c != '\0'; ++c) packet[n++] = *c;
    for (const char* c = what; *c != '\0' && n < sizeof(packet); ++c) packet[n++] = *c;
    send(link::kLinkFd, packet, n, MSG_NOSIGNAL);
    _exit(4);
  }

  static void CatchFaults() {
    static char stack[64 * 1024];
    stack_t alt{};
    alt.ss_sp = stack;
    alt.ss_size = sizeof(stack);
    sigaltstack(&alt, nullptr);  // a stack overflow still reaches the handler
    struct sigaction sa {};
    sa.sa_handler = &OnFault;
    sa.sa_flags = SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    for (const int s : {SIGSEGV, SIGBUS, SIGILL, SIGFPE, SIGABRT}) sigaction(s, &sa, nullptr);
  }

  void SendPacket(const std::vector<uint8_t>& packet) {
    while (send(link::kLinkFd, packet.data(), packet.size(), MSG_NOSIGNAL) < 0) {
      if (errno != EINTR) _exit(0);  // the runner is gone
    }
  }

  // Blocks for the runner's next packet, into `rx_packet` (reused: one
  // arrives per grant); the runner gone ends the process.
  link::Reader ReceivePacket() {
    rx_packet.resize(kMaxRunPacketBytes);
    for (;;) {
      const ssize_t n = recv(link::kLinkFd, rx_packet.data(), rx_packet.size(), 0);
      if (n > 0) return link::Reader(rx_packet.data(), static_cast<size_t>(n));
      if (n == 0 || errno != EINTR) _exit(0);
    }
  }

  void ReceiveAttach() {
    link::Reader r = ReceivePacket();
    if (r.Get(1) != static_cast<uint8_t>(link::Type::kAttach)) Fatal("the runner sent no attach");
    protocol_port = static_cast<int>(r.Get(1)) & 3;
    while (r.left() >= 2) {
      const size_t pin = r.Get(2);
      if (pin < watched.size()) watched[pin] = true;
    }
  }

  [[noreturn]] void Fatal(const std::string& why) {
    std::vector<uint8_t> stopped{static_cast<uint8_t>(link::Type::kStopped),
                                 static_cast<uint8_t>(link::Fault::kRefused)};
    stopped.insert(stopped.end(), why.begin(), why.end());
    Flush();
    SendPacket(stopped);
    _exit(3);
  }

  void Flush() {
    if (out_packet.size() > 1) SendPacket(out_packet);
    if (edge_packet.size() > 1) SendPacket(edge_packet);
    out_packet.clear();
    edge_packet.clear();
    for (const std::string& n : pending_notes) {
      std::vector<uint8_t> note{static_cast<uint8_t>(link::Type::kNote)};
      note.insert(note.end(), n.begin(), n.end());
      SendPacket(note);
    }
    pending_notes.clear();
  }

  void AddOutput(uint8_t value) {
    if (out_packet.size() + link::kOutputRecord > link::kMaxPacketBytes) Flush();
    if (out_packet.empty()) out_packet.push_back(static_cast<uint8_t>(link::Type::kOutput));
    link::Put(out_packet, static_cast<uint64_t>(now_ns), 8);
    out_packet.push_back(value);
    if (stop_at_output) grant_ns = std::min(grant_ns, now_ns);
  }

  void AddEdge(int pin, bool level) {
    if (edge_packet.size() + link::kEdgeRecord > link::kMaxPacketBytes) Flush();
    if (edge_packet.empty()) edge_packet.push_back(static_cast<uint8_t>(link::Type::kEdges));
    link::Put(edge_packet, static_cast<uint64_t>(now_ns), 8);
    link::Put(edge_packet, static_cast<uint64_t>(pin), 2);
    edge_packet.push_back(level ? 1 : 0);
  }

  // Reports the time reached and waits for the next grant.
  void AwaitGrant() {
    Flush();
    const SerialPort& p = ports[protocol_port];
    std::vector<uint8_t> yield{static_cast<uint8_t>(link::Type::kYield)};
    link::Put(yield, static_cast<uint64_t>(now_ns), 8);
    link::Put(yield, static_cast<uint64_t>(std::max(p.line_free_ns, now_ns)), 8);
    link::Put(yield, static_cast<uint64_t>(p.usb ? 0 : p.frame_ns), 8);
    link::Put(yield, dropped, 4);
    dropped = 0;
    SendPacket(yield);
    link::Reader r = ReceivePacket();
    if (r.Get(1) != static_cast<uint8_t>(link::Type::kRun)) Fatal("the runner sent no run");
    grant_ns = r.GetI64();
    stop_at_output = r.Get(1) != 0;
    const std::string_view bytes = r.Rest();
    SerialPort& q = ports[protocol_port];
    for (const char c : bytes) {
      TimeNs at = now_ns;
      if (!q.usb && q.begun) {
        at = std::max(q.line_free_ns, now_ns) + q.frame_ns;
        q.line_free_ns = at;
      }
      q.line.push_back({at, static_cast<uint8_t>(c)});
    }
    next_event_ns = std::min(next_event_ns, q.line.empty() ? kNever : q.line.front().at_ns);
  }

  TimeNs NextEvent() const {
    TimeNs next = kNever;
    for (const Timer& t : timers)
      if (t.running) next = std::min(next, t.due_ns);
    for (const SerialPort& p : ports) {
      if (!p.line.empty() && !(p.usb && p.rx.size() >= p.rx_capacity))
        next = std::min(next, p.line.front().at_ns);
      if (p.shifting) next = std::min(next, p.shift_done_ns);
    }
    return next;
  }

  void RunIsr(Timer& t) {
    void (*isr)() = t.isr;
    if (isr == nullptr) return;
    in_isr = true;
    isr();
    in_isr = false;
    RunPendingIsrs();  // what fell due while it ran
  }

  void RunPendingIsrs() {
    for (size_t i = 0; i < timers.size() && InterruptsEnabled(); ++i) {
      if (!timers[i].pending) continue;
      timers[i].pending = false;
      RunIsr(timers[i]);
    }
  }

  void StartShifting(SerialPort& p) {
    if (p.shifting || p.tx.empty()) return;
    p.shifting = true;
    p.shifting_value = p.tx.front();
    p.tx.pop_front();
    p.shift_done_ns = now_ns + p.frame_ns;
    next_event_ns = std::min(next_event_ns, p.shift_done_ns);
  }

  // Everything due at now_ns: serial bytes first (hardware), then timers.
  void RunEventsDue() {
    for (int i = 0; i < 4; ++i) {
      SerialPort& p = ports[i];
      while (!p.line.empty() && p.line.front().at_ns <= now_ns) {
        if (p.usb && p.rx.size() >= p.rx_capacity) break;  // the host waits
        const uint8_t v = p.line.front().value;
        p.line.pop_front();
        if (!p.begun) continue;  // the receiver is off: lost, as on the wire
        if (p.rx.size() >= p.rx_capacity) {
          ++dropped;
          continue;
        }
        p.rx.push_back(v);
      }
      if (p.shifting && p.shift_done_ns <= now_ns) {
        p.shifting = false;
        p.shift_done_ns = kNever;
        if (i == protocol_port) AddOutput(p.shifting_value);
        StartShifting(p);
      }
    }
    for (size_t i = 0; i < timers.size(); ++i) {
      Timer& t = timers[i];  // an ISR may add timers: no reference outlives it
      if (!t.running || t.due_ns > now_ns) continue;
      if (t.period_ns > 0) {
        t.due_ns += t.period_ns;
      } else {
        t.running = false;
        t.due_ns = kNever;
      }
      if (InterruptsEnabled()) {
        RunIsr(t);
      } else {
        t.pending = true;
      }
    }
  }

  void SpendTo(TimeNs target_ns) {
    if (!connected) Connect();
    for (;;) {
      next_event_ns = NextEvent();
      const TimeNs stop = std::min(target_ns, grant_ns);
      if (next_event_ns <= stop) {
        now_ns = std::max(now_ns, next_event_ns);
        RunEventsDue();
        continue;
      }
      if (target_ns <= grant_ns) {
        now_ns = std::max(now_ns, target_ns);
        return;
      }
      now_ns = std::max(now_ns, grant_ns);
      AwaitGrant();
    }
  }
};

Runtime& Rt() {
  static Runtime* runtime = new Runtime();  // never destroyed: the sketch may run at exit
  return *runtime;
}

Timer* TimerAt(int id) {
  Runtime& rt = Rt();
  if (id < 0 || static_cast<size_t>(id) >= rt.timers.size()) return nullptr;
  return &rt.timers[static_cast<size_t>(id)];
}

SerialPort* PortAt(int port) { return port >= 0 && port < 4 ? &Rt().ports[port] : nullptr; }

}  // namespace

TimeNs Now() { return Rt().now_ns; }

void Spend(TimeNs ns) {
  Runtime& rt = Rt();
  const TimeNs target = rt.now_ns + std::max<TimeNs>(ns, 0);
  if (target < rt.next_event_ns && target <= rt.grant_ns) {
    rt.now_ns = target;
    return;
  }
  rt.SpendTo(target);
}

void ClockRead() { Spend(TheBoard().clock_read_ns); }
void Call() { Spend(TheBoard().call_ns); }

void WaitForEvent() {
  Runtime& rt = Rt();
  if (!rt.connected) rt.Connect();
  const TimeNs next = rt.NextEvent();
  if (next != kNever) {
    rt.SpendTo(std::max(next, rt.now_ns));
  } else if (rt.now_ns < rt.grant_ns) {
    rt.SpendTo(rt.grant_ns);  // nothing can happen before the runner's next grant
  } else {
    rt.AwaitGrant();  // which may bring host bytes: the caller looks again
  }
}

void InterruptsOff() { Rt().irq_flag = false; }
void InterruptsOn() {
  Runtime& rt = Rt();
  rt.irq_flag = true;
  rt.RunPendingIsrs();
}
void EnterCritical() { ++Rt().critical; }
void ExitCritical() {
  Runtime& rt = Rt();
  if (rt.critical > 0) --rt.critical;
  rt.RunPendingIsrs();
}

int TimerCreate() {
  Runtime& rt = Rt();
  rt.timers.emplace_back();
  return static_cast<int>(rt.timers.size() - 1);
}

void TimerAttach(int id, void (*isr)()) {
  if (Timer* t = TimerAt(id)) t->isr = isr;
}

void TimerStart(int id, TimeNs first_ns, TimeNs period_ns) {
  Timer* t = TimerAt(id);
  if (t == nullptr) return;
  Runtime& rt = Rt();
  t->running = true;
  t->pending = false;
  t->started_ns = rt.now_ns;
  t->due_ns = rt.now_ns + std::max<TimeNs>(first_ns, 1);
  t->period_ns = std::max<TimeNs>(period_ns, 0);
  rt.next_event_ns = std::min(rt.next_event_ns, t->due_ns);
}

void TimerStop(int id) {
  if (Timer* t = TimerAt(id)) {
    t->running = false;
    t->pending = false;
    t->due_ns = kNever;
  }
}

bool TimerRunning(int id) {
  const Timer* t = TimerAt(id);
  return t != nullptr && t->running;
}

TimeNs TimerElapsed(int id) {
  const Timer* t = TimerAt(id);
  return t != nullptr && t->running ? Rt().now_ns - t->started_ns : 0;
}

void PinMode(int /*pin*/, int /*mode*/) { Call(); }

void PinWrite(int pin, bool level) {
  Runtime& rt = Rt();
  if (!rt.connected) rt.Connect();
  if (pin < 0 || static_cast<size_t>(pin) >= rt.levels.size()) return;
  if (rt.levels[static_cast<size_t>(pin)] == level) return;
  rt.levels[static_cast<size_t>(pin)] = level;
  if (rt.watched[static_cast<size_t>(pin)]) rt.AddEdge(pin, level);
}

bool PinRead(int pin) {
  Call();
  Runtime& rt = Rt();
  return pin >= 0 && static_cast<size_t>(pin) < rt.levels.size() &&
         rt.levels[static_cast<size_t>(pin)] != 0;
}

void PortWrite(char port, uint8_t before, uint8_t after) {
  const BoardSpec& b = TheBoard();
  Spend(b.port_write_ns);
  const uint8_t changed = before ^ after;
  if (changed == 0) return;
  Runtime& rt = Rt();
  for (size_t i = 0; i < b.port_map_size; ++i) {
    const PortPin& pp = b.port_map[i];
    if (pp.port != port || (changed & (1u << pp.bit)) == 0) continue;
    const bool level = (after >> pp.bit) & 1;
    if (pp.pin >= rt.levels.size()) continue;
    rt.levels[pp.pin] = level;
    if (rt.watched[pp.pin]) rt.AddEdge(pp.pin, level);
  }
}

void Note(const char* what) {
  Runtime& rt = Rt();
  if (rt.notes.insert(what).second) rt.pending_notes.emplace_back(what);
}

void Stop(const char* why) {
  Runtime& rt = Rt();
  if (!rt.connected) rt.Connect();
  rt.Fatal(why);
}

void SerialBegin(int port, uint32_t baud) {
  Call();
  SerialPort* p = PortAt(port);
  if (p == nullptr) return;
  p->begun = true;
  p->baud = baud == 0 ? 9600 : baud;
  // 8N1: ten bit times a byte.
  p->frame_ns = static_cast<TimeNs>((10ull * 1000000000ull + p->baud - 1) / p->baud);
  if (p->usb) p->frame_ns = 0;
}

void SerialEnd(int port) {
  Call();
  if (SerialPort* p = PortAt(port)) p->begun = false;
}

int SerialAvailable(int port) {
  Call();
  const SerialPort* p = PortAt(port);
  return p == nullptr ? 0 : static_cast<int>(p->rx.size());
}

int SerialRead(int port) {
  Call();
  SerialPort* p = PortAt(port);
  if (p == nullptr || p->rx.empty()) return -1;
  const uint8_t v = p->rx.front();
  p->rx.pop_front();
  if (p->usb && !p->line.empty()) {
    // The host's bytes held back by a full buffer come in now.
    Runtime& rt = Rt();
    rt.next_event_ns = std::min(rt.next_event_ns, std::max(rt.now_ns, p->line.front().at_ns));
  }
  return v;
}

int SerialPeek(int port) {
  Call();
  const SerialPort* p = PortAt(port);
  return p == nullptr || p->rx.empty() ? -1 : p->rx.front();
}

int SerialAvailableForWrite(int port) {
  Call();
  const SerialPort* p = PortAt(port);
  if (p == nullptr) return 0;
  return static_cast<int>(p->tx_capacity - std::min(p->tx_capacity, p->tx.size()));
}

void SerialWrite(int port, uint8_t value) {
  Call();
  SerialPort* p = PortAt(port);
  if (p == nullptr || !p->begun) return;
  Runtime& rt = Rt();
  if (p->usb) {
    if (port == rt.protocol_port) rt.AddOutput(value);
    return;
  }
  while (p->tx.size() >= p->tx_capacity) WaitForEvent();
  p->tx.push_back(value);
  rt.StartShifting(*p);
}

void SerialFlush(int port) {
  Call();
  SerialPort* p = PortAt(port);
  while (p != nullptr && (p->shifting || !p->tx.empty())) WaitForEvent();
}

uint8_t EepromRead(size_t address) {
  Call();
  Runtime& rt = Rt();
  if (!rt.connected) rt.Connect();
  return address < rt.eeprom.size() ? rt.eeprom[address] : 0xFF;
}

void EepromWrite(size_t address, uint8_t value) {
  Call();
  Runtime& rt = Rt();
  if (!rt.connected) rt.Connect();
  if (address < rt.eeprom.size()) rt.eeprom[address] = value;
}

std::vector<AddedCore>& AddedCores() {
  static auto* cores = new std::vector<AddedCore>();
  return *cores;
}

void AddCore(void (*setup)(), void (*loop)()) { AddedCores().push_back({setup, loop}); }

void StartFirmware() {
  Runtime& rt = Rt();
  if (!rt.connected) rt.Connect();
}

}  // namespace moco::arduino
