// Test bench for the DFMoco device in virtual time: the device's writes
// recorded with the scheduler's time (devices/test_support.h), and helpers to
// feed host lines.
#ifndef MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_TEST_SUPPORT_H_
#define MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_TEST_SUPPORT_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "devices/device.h"
#include "devices/dfmoco_arduino/dfmoco_arduino.h"
#include "devices/test_support.h"
#include "sim/scheduler.h"

namespace moco::devices::testing {

// One output line (terminator removed) and the time its chunk was written.
struct TimedLine {
  sim::TimeNs t_ns = 0;
  std::string text;
};

struct Bench {
  explicit Bench(DfmocoProfile profile = {}, bool power_on = true)
      : sink(sched), dev(sched, sink, std::move(profile)) {
    if (power_on) dev.PowerOn();
  }
  void Host(std::string_view bytes) {
    dev.OnHostBytes(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
  }
  // Sends `line` + "\r\n".
  void Line(std::string_view line) { Host(std::string(line) + "\r\n"); }
  void RunUntil(sim::TimeNs t) { sched.RunUntil(t); }
  void RunFor(sim::TimeNs d) { sched.RunUntil(sched.Now() + d); }
  // Every line written since the last call, in order.
  std::vector<TimedLine> TakeLines() {
    std::vector<TimedLine> out;
    for (; taken < sink.chunks.size(); ++taken) {
      const RecordingSink::Chunk& c = sink.chunks[taken];
      pending += c.bytes;
      size_t pos = 0;
      while ((pos = pending.find("\r\n")) != std::string::npos) {
        out.push_back(TimedLine{c.t_ns, pending.substr(0, pos)});
        pending.erase(0, pos + 2);
      }
    }
    return out;
  }
  std::vector<std::string> TakeTexts() {
    std::vector<std::string> out;
    for (TimedLine& l : TakeLines()) out.push_back(std::move(l.text));
    return out;
  }

  sim::Scheduler sched;
  RecordingSink sink;
  DfmocoArduino dev;
  size_t taken = 0;
  std::string pending;
};

}  // namespace moco::devices::testing

#endif  // MOCO_DEVICES_DFMOCO_ARDUINO_DFMOCO_TEST_SUPPORT_H_
