// A ByteSink that records a device's output into a session file with the
// scheduler time of each write (docs/sessions.md), for writing golden
// sessions of devices run in virtual time.
#ifndef MOCO_CONTROL_DEVICE_RECORDER_H_
#define MOCO_CONTROL_DEVICE_RECORDER_H_

#include "control/session.h"
#include "devices/device.h"
#include "sim/scheduler.h"

namespace moco::control {

class DeviceRecorder final : public devices::ByteSink {
 public:
  // `scheduler` and `writer` must outlive the recorder.
  DeviceRecorder(const sim::Scheduler& scheduler, SessionWriter& writer)
      : scheduler_(scheduler), writer_(writer) {}
  void Write(wire::ByteView bytes) override { Append(Origin::kDevice, bytes); }
  // Records host bytes at the current time (call just before handing them to the device).
  void Host(wire::ByteView bytes) { Append(Origin::kHost, bytes); }

 private:
  void Append(Origin from, wire::ByteView bytes) {
    SessionEntry e;
    e.t_ns = scheduler_.Now();
    e.from = from;
    e.bytes.assign(bytes.begin(), bytes.end());
    writer_.Append(e);
  }
  const sim::Scheduler& scheduler_;
  SessionWriter& writer_;
};

}  // namespace moco::control

#endif  // MOCO_CONTROL_DEVICE_RECORDER_H_
