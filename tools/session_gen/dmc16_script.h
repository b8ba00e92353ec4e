// A scripted DMC v2 host against a DMC-16 in virtual time, recorded into a
// session file (docs/sessions.md): what the DMC-16 session generators share.
// Each request is sent at its time with the next host ID; the device's
// answers are recorded at the scheduler time they are written.
#ifndef MOCO_TOOLS_SESSION_GEN_DMC16_SCRIPT_H_
#define MOCO_TOOLS_SESSION_GEN_DMC16_SCRIPT_H_

#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>

#include "devices/dmc16/dmc16.h"
#include "session/session.h"
#include "sim/scheduler.h"
#include "tools/session_gen/device_recorder.h"
#include "wire/dmc.h"

namespace moco::session_gen {

class Dmc16Script {
 public:
  // Opens `path` with a DMC v2 virtual-clock header carrying `note`, and
  // powers on a DMC-16 with `profile` at t = 0. Host IDs count from `first_id`.
  Dmc16Script(const std::string& path, std::string note, devices::Dmc16Profile profile,
              uint32_t first_id)
      : writer_(path, Header(std::move(note))),
        sink_(scheduler_, writer_),
        device_(scheduler_, sink_, std::move(profile)),
        next_id_(first_id) {
    device_.PowerOn();
  }

  // Runs the clock to `t_ns` and sends `bytes` as they are.
  void SendBytes(sim::TimeNs t_ns, const wire::Bytes& bytes) {
    scheduler_.RunUntil(t_ns);
    sink_.Host(bytes);
    device_.OnHostBytes(bytes);
  }
  // Runs the clock to `t_ns` and sends `m` with the next host ID.
  void Send(sim::TimeNs t_ns, const dmc::HostMessage& m) { SendBytes(t_ns, Encode(m)); }
  // `m` encoded with the next host ID (to damage it before SendBytes).
  wire::Bytes Encode(const dmc::HostMessage& m) { return dmc::Encode(next_id_++, m); }

  // Runs the clock to `t_ns` and completes the file; false (and a message
  // naming `tool` on stderr) when it could not be written.
  bool Finish(sim::TimeNs t_ns, const char* tool) {
    scheduler_.RunUntil(t_ns);
    std::string error;
    if (writer_.Finish(&error)) return true;
    std::fprintf(stderr, "%s: %s\n", tool, error.c_str());
    return false;
  }

  const devices::Dmc16& device() const { return device_; }

 private:
  static session::SessionHeader Header(std::string note) {
    session::SessionHeader h;
    h.protocol = wire::Protocol::kDmc;
    h.device = "dmc16";
    h.clock = "virtual";
    h.note = std::move(note);
    return h;
  }

  session::SessionWriter writer_;
  sim::Scheduler scheduler_;
  DeviceRecorder sink_;
  devices::Dmc16 device_;
  uint32_t next_id_;
};

// Seconds on the virtual clock, as the scripts write their times.
inline sim::TimeNs Seconds(double s) { return static_cast<sim::TimeNs>(s * 1e9); }

}  // namespace moco::session_gen

#endif  // MOCO_TOOLS_SESSION_GEN_DMC16_SCRIPT_H_
