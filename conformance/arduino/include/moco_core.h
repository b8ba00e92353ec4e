// The host Arduino core's clock, interrupts, pins and serial ports, as the
// Arduino headers of conformance/arduino/include call them (conformance/arduino
// /link.h says how the runner drives them). Simulated time moves only at these
// calls: each costs the board's figure (a clock read, a call, a port write),
// a wait moves it to the end of the wait, and timer interrupts and serial
// bytes happen at their exact times within that span. One thread: the sketch's.
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_MOCO_CORE_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_MOCO_CORE_H_

#include <stddef.h>
#include <stdint.h>

namespace moco::arduino {

using TimeNs = int64_t;

// One bit of a board's I/O port that a direct port write reaches: PORTD bit 4
// drives pin 4 on an Uno.
struct PortPin {
  uint16_t pin;
  char port;
  uint8_t bit;
};

// What a board gives a sketch: its name, pins, serial buffers and the cost of
// the core's calls in simulated time. Each board file (conformance/arduino/
// boards/NAME.cpp) defines TheBoard(); its header NAME.h, included before the
// sketch, says which API set the sketch sees.
struct BoardSpec {
  const char* name;
  int pins;                     // digital pins 0..pins-1
  size_t uart_rx_buffer_bytes;  // a hardware serial port's receive buffer
  size_t uart_tx_buffer_bytes;  // and its transmit buffer
  bool serial_is_usb;           // Serial is USB CDC: not paced, never drops
  size_t usb_buffer_bytes;      // its buffers, when it is
  TimeNs clock_read_ns;         // millis(), micros()
  TimeNs call_ns;               // any other call into the core
  TimeNs port_write_ns;         // a direct port write (PORTD = ...)
  const PortPin* port_map;      // direct port bits -> pins (may be empty)
  size_t port_map_size;
  size_t eeprom_bytes;
};
const BoardSpec& TheBoard();

// Simulated time since the firmware started, without cost.
TimeNs Now();
// Time passes in the sketch: `ns` (>= 0) of simulated time, with every timer
// interrupt and serial byte due in that span happening at its time.
void Spend(TimeNs ns);
// The costs of the board's calls (BoardSpec), each a Spend().
void ClockRead();
void Call();
// Waits until the next timer interrupt or serial byte (an AVR's sleep_cpu()).
void WaitForEvent();

// Interrupts: off and on as cli()/sei() (not counted) and as a critical
// section (counted, portENTER_CRITICAL). A timer due while they are off runs
// when they come back on, once.
void InterruptsOff();
void InterruptsOn();
void EnterCritical();
void ExitCritical();

// A periodic (or one-shot: period 0) timer interrupt. Create() gives an id;
// Start() fires `isr` first `first_ns` from now, then every `period_ns`.
int TimerCreate();
void TimerAttach(int id, void (*isr)());
void TimerStart(int id, TimeNs first_ns, TimeNs period_ns);
void TimerStop(int id);
bool TimerRunning(int id);
// Time since the timer was started, 0 when it is stopped.
TimeNs TimerElapsed(int id);

// Pins. Write() records an edge for a watched pin at the current time, and
// costs nothing itself (digitalWrite() adds a call's cost first).
void PinMode(int pin, int mode);
void PinWrite(int pin, bool level);
bool PinRead(int pin);
// A direct write of an 8-bit port: every changed bit the board's port map
// names is an edge at the same time (one port write, one instant).
void PortWrite(char port, uint8_t before, uint8_t after);

// A second core of a dual-core board, run by a user's glue file beside the
// sketch on the same clock (docs/firmware-ci.md): `setup` once before the
// sketch's setup(), `loop` (may be null: a core that only serves interrupts)
// after each return of the sketch's loop(). Call it from a static
// initializer of the glue file. The added setup runs to its end first, on
// the one clock: a wait in it delays the sketch's setup too, where on the
// board the cores run side by side (a glue can give the second core's
// delay() a clock of its own, as fixtures/firmware/glue/dmc_lite_giga does).
void AddCore(void (*setup)(), void (*loop)());

// Says once (per `what`) that the sketch used something the core does not
// model; the run report lists it.
void Note(const char* what);
// Stops the firmware for good with `why` (an API the core refuses).
[[noreturn]] void Stop(const char* why);

// Serial ports: 0-2 are Serial, Serial1, Serial2; 3 is a Bluetooth serial port.
inline constexpr int kBluetoothPort = 3;
void SerialBegin(int port, uint32_t baud);
void SerialEnd(int port);
int SerialAvailable(int port);
int SerialRead(int port);
int SerialPeek(int port);
int SerialAvailableForWrite(int port);
// Blocks (in simulated time) while the transmit buffer is full.
void SerialWrite(int port, uint8_t value);
// Until the transmit buffer and shift register are empty.
void SerialFlush(int port);

// EEPROM: the board's bytes, erased (0xFF) at start.
uint8_t EepromRead(size_t address);
void EepromWrite(size_t address, uint8_t value);

}  // namespace moco::arduino

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_MOCO_CORE_H_
