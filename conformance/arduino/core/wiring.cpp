// The Arduino API's clock, pins and interrupts on the host core
// (include/Arduino.h), and the board timer APIs built on the core's timers:
// the ESP32's hw_timer (esp32-hal.h), Teensy's IntervalTimer, TimerOne.
#include <math.h>
#include <stdio.h>

#include <cstdint>

#include "Arduino.h"
#include "EEPROM.h"
#include "IntervalTimer.h"
#include "TimerOne.h"
#include "esp32-hal.h"

namespace ar = moco::arduino;

unsigned long millis() {
  ar::ClockRead();
  return static_cast<unsigned long>(static_cast<uint32_t>(ar::Now() / 1000000));
}

unsigned long micros() {
  ar::ClockRead();
  return static_cast<unsigned long>(static_cast<uint32_t>(ar::Now() / 1000));
}

void delay(unsigned long ms) {
  ar::Call();
  ar::Spend(static_cast<ar::TimeNs>(ms) * 1000000);
}

void delayMicroseconds(unsigned int us) {
  ar::Call();
  ar::Spend(static_cast<ar::TimeNs>(us) * 1000);
}

void yield() { ar::Call(); }

void pinMode(uint8_t pin, uint8_t mode) { ar::PinMode(pin, mode); }
void digitalWrite(uint8_t pin, uint8_t level) {
  ar::Call();
  ar::PinWrite(pin, level != LOW);
}
int digitalRead(uint8_t pin) { return ar::PinRead(pin) ? HIGH : LOW; }

int analogRead(uint8_t /*pin*/) {
  ar::Call();
  ar::Note("analogRead(): the runner drives no analog input; every read gives 0");
  return 0;
}

void analogWrite(uint8_t pin, int value) {
  ar::Note("analogWrite(): PWM is not modelled; a pin is high at 255 and low below");
  ar::Call();
  ar::PinWrite(pin, value >= 255);
}

void analogReference(uint8_t /*mode*/) { ar::Call(); }

void attachInterrupt(uint8_t /*interrupt*/, void (* /*isr*/)(), int /*mode*/) {
  ar::Call();
  ar::Note("attachInterrupt(): the runner drives no input pin, so pin interrupts never fire");
}
void detachInterrupt(uint8_t /*interrupt*/) { ar::Call(); }

void tone(uint8_t /*pin*/, unsigned int /*frequency*/, unsigned long /*duration_ms*/) {
  ar::Call();
  ar::Note("tone(): not modelled; the pin does not toggle");
}
void noTone(uint8_t /*pin*/) { ar::Call(); }

unsigned long pulseIn(uint8_t /*pin*/, uint8_t /*state*/, unsigned long timeout_us) {
  ar::Note("pulseIn(): the runner drives no input pin; it times out");
  ar::Spend(static_cast<ar::TimeNs>(timeout_us) * 1000);
  return 0;
}

void shiftOut(uint8_t data_pin, uint8_t clock_pin, uint8_t bit_order, uint8_t value) {
  for (int i = 0; i < 8; ++i) {
    const int b = bit_order == LSBFIRST ? i : 7 - i;
    digitalWrite(data_pin, (value >> b) & 1);
    digitalWrite(clock_pin, HIGH);
    digitalWrite(clock_pin, LOW);
  }
}

long map(long x, long in_min, long in_max, long out_min, long out_max) {
  if (in_max == in_min) return out_min;
  return (x - in_min) * (out_max - out_min) / (in_max - in_min) + out_min;
}

namespace {
char* ToText(unsigned long magnitude, bool negative, char* buffer, int base) {
  if (base < 2 || base > 36) base = 10;
  char digits[72];
  int n = 0;
  do {
    const int d = static_cast<int>(magnitude % static_cast<unsigned>(base));
    digits[n++] = static_cast<char>(d < 10 ? '0' + d : 'a' + d - 10);
    magnitude /= static_cast<unsigned>(base);
  } while (magnitude != 0);
  char* p = buffer;
  if (negative) *p++ = '-';
  while (n > 0) *p++ = digits[--n];
  *p = '\0';
  return buffer;
}
}  // namespace

char* ltoa(long value, char* buffer, int base) {
  const bool negative = value < 0 && base == 10;
  const unsigned long magnitude =
      negative ? 0ul - static_cast<unsigned long>(value) : static_cast<unsigned long>(value);
  return ToText(magnitude, negative, buffer, base);
}
char* itoa(int value, char* buffer, int base) {
  if (base != 10 && value < 0) return ToText(static_cast<unsigned>(value), false, buffer, base);
  return ltoa(value, buffer, base);
}
char* utoa(unsigned value, char* buffer, int base) { return ToText(value, false, buffer, base); }
char* ultoa(unsigned long value, char* buffer, int base) {
  return ToText(value, false, buffer, base);
}
char* dtostrf(double value, signed char width, unsigned char precision, char* buffer) {
  snprintf(buffer, 64, "%*.*f", width, precision, value);
  return buffer;
}

word makeWord(uint8_t high, uint8_t low) { return static_cast<word>((high << 8) | low); }

namespace {
uint64_t random_state = 0x2545F4914F6CDD1Dull;
uint32_t NextRandom() {
  random_state ^= random_state >> 12;
  random_state ^= random_state << 25;
  random_state ^= random_state >> 27;
  return static_cast<uint32_t>((random_state * 0x2545F4914F6CDD1Dull) >> 32);
}
}  // namespace

long random(long max) { return max <= 0 ? 0 : static_cast<long>(NextRandom() % max); }
long random(long min, long max) { return min >= max ? min : min + random(max - min); }
void randomSeed(unsigned long seed) {
  if (seed != 0) random_state = seed * 0x9E3779B97F4A7C15ull | 1;
}

// --- ESP32 hw_timer ---------------------------------------------------------------

struct hw_timer_s {
  int id = -1;
  uint16_t divider = 80;
  uint64_t alarm = 0;
  bool autoreload = false;
  bool alarm_enabled = false;
  bool counting = true;
  uint64_t count_base = 0;  // counts at the last start or write
};

namespace {
constexpr uint64_t kApbHz = 80000000;
hw_timer_s esp_timers[4];

// Counts -> nanoseconds at the timer's prescaler (exact to the nanosecond).
ar::TimeNs CountsToNs(const hw_timer_s& t, uint64_t counts) {
  return static_cast<ar::TimeNs>(counts * t.divider * 1000000000ull / kApbHz);
}

void Rearm(hw_timer_s& t) {
  ar::TimerStop(t.id);
  if (!t.alarm_enabled || !t.counting) return;
  const uint64_t now = timerRead(&t);
  const uint64_t to_alarm = t.alarm > now ? t.alarm - now : 1;
  ar::TimerStart(t.id, CountsToNs(t, to_alarm), t.autoreload ? CountsToNs(t, t.alarm) : 0);
}
}  // namespace

hw_timer_t* timerBegin(uint8_t num, uint16_t divider, bool /*count_up*/) {
  ar::Call();
  if (num > 3) ar::Stop("timerBegin(): the ESP32 has timers 0 to 3");
  hw_timer_s& t = esp_timers[num];
  if (t.id < 0) t.id = ar::TimerCreate();
  t.divider = divider < 2 ? 2 : divider;
  t.alarm_enabled = false;
  t.counting = true;
  t.count_base = 0;
  ar::TimerStop(t.id);
  return &t;
}

void timerEnd(hw_timer_t* timer) {
  ar::Call();
  if (timer == nullptr) return;
  timer->alarm_enabled = false;
  ar::TimerStop(timer->id);
}

void timerAttachInterrupt(hw_timer_t* timer, void (*isr)(), bool /*edge*/) {
  ar::Call();
  if (timer != nullptr) ar::TimerAttach(timer->id, isr);
}

void timerDetachInterrupt(hw_timer_t* timer) {
  ar::Call();
  if (timer != nullptr) ar::TimerAttach(timer->id, nullptr);
}

void timerAlarmWrite(hw_timer_t* timer, uint64_t alarm_value, bool autoreload) {
  ar::Call();
  if (timer == nullptr) return;
  timer->alarm = alarm_value == 0 ? 1 : alarm_value;
  timer->autoreload = autoreload;
  Rearm(*timer);
}

void timerAlarmEnable(hw_timer_t* timer) {
  ar::Call();
  if (timer == nullptr) return;
  timer->alarm_enabled = true;
  Rearm(*timer);
}

void timerAlarmDisable(hw_timer_t* timer) {
  ar::Call();
  if (timer == nullptr) return;
  timer->alarm_enabled = false;
  Rearm(*timer);
}

bool timerAlarmEnabled(hw_timer_t* timer) { return timer != nullptr && timer->alarm_enabled; }

void timerStart(hw_timer_t* timer) {
  ar::Call();
  if (timer == nullptr || timer->counting) return;
  timer->counting = true;
  Rearm(*timer);
}

void timerStop(hw_timer_t* timer) {
  ar::Call();
  if (timer == nullptr) return;
  timer->count_base = timerRead(timer);
  timer->counting = false;
  ar::TimerStop(timer->id);
}

void timerRestart(hw_timer_t* timer) { timerWrite(timer, 0); }

void timerWrite(hw_timer_t* timer, uint64_t value) {
  ar::Call();
  if (timer == nullptr) return;
  timer->count_base = value;
  Rearm(*timer);
}

uint64_t timerRead(hw_timer_t* timer) {
  if (timer == nullptr) return 0;
  if (!timer->counting || !ar::TimerRunning(timer->id)) return timer->count_base;
  const uint64_t ns = static_cast<uint64_t>(ar::TimerElapsed(timer->id));
  const uint64_t counts = ns * kApbHz / (1000000000ull * timer->divider);
  return timer->autoreload && timer->alarm > 0 ? counts % timer->alarm : timer->count_base + counts;
}

uint64_t timerReadMicros(hw_timer_t* timer) {
  return timer == nullptr ? 0 : timerRead(timer) * timer->divider / (kApbHz / 1000000);
}

void vTaskDelay(TickType_t ticks) { delay(ticks); }

EspClass ESP;
void EspClass::restart() { ar::Stop("ESP.restart(): the sketch restarted the chip"); }

// --- Teensy IntervalTimer -----------------------------------------------------------

bool IntervalTimer::Begin(void (*isr)(), double period_ns) {
  ar::Call();
  if (isr == nullptr || !(period_ns >= 1)) return false;
  if (id_ < 0) id_ = ar::TimerCreate();
  ar::TimerAttach(id_, isr);
  const auto ns = static_cast<ar::TimeNs>(llround(period_ns));
  ar::TimerStart(id_, ns, ns);
  return true;
}

void IntervalTimer::Update(double period_ns) {
  ar::Call();
  if (id_ < 0 || !ar::TimerRunning(id_) || !(period_ns >= 1)) return;
  const auto ns = static_cast<ar::TimeNs>(llround(period_ns));
  // The new period starts after the current one ends, as on a Teensy.
  const ar::TimeNs elapsed = ar::TimerElapsed(id_);
  (void)elapsed;
  ar::TimerStart(id_, ns, ns);
}

void IntervalTimer::end() {
  if (id_ >= 0) ar::TimerStop(id_);
}

IntervalTimer::operator bool() const { return id_ >= 0 && ar::TimerRunning(id_); }

// --- TimerOne ---------------------------------------------------------------------------

TimerOne Timer1;

int TimerOne::Id() {
  if (id_ < 0) id_ = ar::TimerCreate();
  return id_;
}

void TimerOne::initialize(unsigned long microseconds) {
  ar::Call();
  period_ns_ = static_cast<int64_t>(microseconds) * 1000;
  Id();
}

void TimerOne::setPeriod(unsigned long microseconds) {
  setPeriodNs(static_cast<int64_t>(microseconds) * 1000);
}

void TimerOne::setPeriodNs(int64_t period_ns) {
  ar::Call();
  period_ns_ = period_ns < 1 ? 1 : period_ns;
  if (ar::TimerRunning(Id())) ar::TimerStart(Id(), period_ns_, period_ns_);
}

void TimerOne::attachInterrupt(void (*isr)()) {
  ar::Call();
  ar::TimerAttach(Id(), isr);
  if (!ar::TimerRunning(Id())) ar::TimerStart(Id(), period_ns_, period_ns_);
}

void TimerOne::attachInterrupt(void (*isr)(), unsigned long microseconds) {
  period_ns_ = static_cast<int64_t>(microseconds) * 1000;
  attachInterrupt(isr);
}

void TimerOne::detachInterrupt() {
  ar::Call();
  ar::TimerAttach(Id(), nullptr);
}

void TimerOne::start() {
  ar::Call();
  ar::TimerStart(Id(), period_ns_, period_ns_);
}

void TimerOne::stop() {
  ar::Call();
  ar::TimerStop(Id());
}

void TimerOne::resume() {
  ar::Call();
  if (!ar::TimerRunning(Id())) ar::TimerStart(Id(), period_ns_, period_ns_);
}

unsigned long TimerOne::read() {
  return static_cast<unsigned long>(ar::TimerElapsed(Id()) % period_ns_ / 1000);
}

EEPROMClass EEPROM;
