// The ESP32 Arduino core's (2.x) timer and critical-section API on the host
// core: hw_timer on the 80 MHz APB clock through a prescaler, its alarm firing
// the attached interrupt at its exact simulated time; portMUX critical
// sections as interrupts off (one core runs the sketch); IRAM_ATTR and
// friends accepted; FreeRTOS delays as delay().
#ifndef MOCO_CONFORMANCE_ARDUINO_INCLUDE_ESP32_HAL_H_
#define MOCO_CONFORMANCE_ARDUINO_INCLUDE_ESP32_HAL_H_

#include <stdint.h>

#include "moco_core.h"

#define IRAM_ATTR
#define DRAM_ATTR
#define ARDUINO_ISR_ATTR

struct hw_timer_s;
typedef struct hw_timer_s hw_timer_t;

// Timer `num` (0..3) counting APB ticks divided by `divider` (2..65535).
hw_timer_t* timerBegin(uint8_t num, uint16_t divider, bool count_up);
void timerEnd(hw_timer_t* timer);
void timerAttachInterrupt(hw_timer_t* timer, void (*isr)(), bool edge);
void timerDetachInterrupt(hw_timer_t* timer);
// The alarm at `alarm_value` counts; with autoreload the count restarts at 0.
void timerAlarmWrite(hw_timer_t* timer, uint64_t alarm_value, bool autoreload);
void timerAlarmEnable(hw_timer_t* timer);
void timerAlarmDisable(hw_timer_t* timer);
bool timerAlarmEnabled(hw_timer_t* timer);
void timerStart(hw_timer_t* timer);
void timerStop(hw_timer_t* timer);
void timerRestart(hw_timer_t* timer);
void timerWrite(hw_timer_t* timer, uint64_t value);
uint64_t timerRead(hw_timer_t* timer);
uint64_t timerReadMicros(hw_timer_t* timer);

typedef struct {
  uint32_t owner;
  uint32_t count;
} portMUX_TYPE;
#define portMUX_INITIALIZER_UNLOCKED \
  { 0, 0 }
#define portENTER_CRITICAL(mux) ((void)(mux), moco::arduino::EnterCritical())
#define portEXIT_CRITICAL(mux) ((void)(mux), moco::arduino::ExitCritical())
#define portENTER_CRITICAL_ISR(mux) portENTER_CRITICAL(mux)
#define portEXIT_CRITICAL_ISR(mux) portEXIT_CRITICAL(mux)
#define portENTER_CRITICAL_SAFE(mux) portENTER_CRITICAL(mux)
#define portEXIT_CRITICAL_SAFE(mux) portEXIT_CRITICAL(mux)
#define portTICK_PERIOD_MS 1
#define pdMS_TO_TICKS(ms) (ms)
typedef uint32_t TickType_t;
void vTaskDelay(TickType_t ticks);

// ESP.restart() and the chip queries a sketch commonly makes.
class EspClass {
 public:
  [[noreturn]] void restart();
  uint32_t getFreeHeap() { return 320 * 1024; }
  uint32_t getCpuFreqMHz() { return 240; }
};
extern EspClass ESP;

#endif  // MOCO_CONFORMANCE_ARDUINO_INCLUDE_ESP32_HAL_H_
