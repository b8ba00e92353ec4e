// A ByteSink that records a device's output into a session file with the
// scheduler time of each write (docs/sessions.md), for writing golden
// sessions of devices run in virtual time.
#ifndef MOCO_TOOLS_SESSION_GEN_DEVICE_RECORDER_H_
#define MOCO_TOOLS_SESSION_GEN_DEVICE_RECORDER_H_

#include "devices/device.h"
#include "session/session.h"
#include "sim/scheduler.h"

namespace moco::session_gen {

class DeviceRecorder final : public devices::ByteSink {
 public:
  // `scheduler` and `writer` must outlive the recorder.
  DeviceRecorder(const sim::Scheduler& scheduler, session::SessionWriter& writer)
      : scheduler_(scheduler), writer_(writer) {}
  void Write(wire::ByteView bytes) override { Append(session::Origin::kDevice, bytes); }
  // Records host bytes at the current time (call just before handing them to the device).
  void Host(wire::ByteView bytes) { Append(session::Origin::kHost, bytes); }

 private:
  void Append(session::Origin from, wire::ByteView bytes) {
    session::SessionEntry e;
    e.t_ns = scheduler_.Now();
    e.from = from;
    e.bytes.assign(bytes.begin(), bytes.end());
    writer_.Append(e);
  }
  const sim::Scheduler& scheduler_;
  session::SessionWriter& writer_;
};

}  // namespace moco::session_gen

#endif  // MOCO_TOOLS_SESSION_GEN_DEVICE_RECORDER_H_
