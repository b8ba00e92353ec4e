// A DMC-16 broken on purpose: the real emulated device with a filter on its
// output (each frame it writes handed to a Breakage) and, optionally, on its
// input (the host's bytes changed before it reads them). The proving tests
// plant faults this way; conformance/broken_device_bench.cpp times whole runs
// against such devices.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_BROKEN_DEVICE_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_BROKEN_DEVICE_H_

#include <functional>
#include <memory>
#include <string>

#include "devices/faulty_sink.h"
#include "devices/registry.h"
#include "wire/dmc.h"

namespace moco::conformance::dmc_testing {

// Decides what becomes of one frame the device wrote: `out` is the real link.
using Breakage = std::function<void(const dmc::FrameRef& f, wire::Bytes raw, sim::Scheduler& s,
                                    devices::ByteSink& out)>;

// What becomes of the host's bytes before the device reads them (a device
// that acts wrongly on a request); empty: read as sent.
using InputBreakage = std::function<wire::Bytes(wire::ByteView host_bytes)>;

// The real DMC-16 with a broken output stage (and, optionally, input stage).
class BrokenDmc16 final : public devices::Device {
 public:
  BrokenDmc16(sim::Scheduler& s, devices::ByteSink& out, Breakage b, const std::string& profile,
              InputBreakage in = {})
      : in_(std::move(in)),
        sink_(out,
              [&s, b = std::move(b)](const dmc::FrameRef& f, devices::ByteSink& o) {
                b(f, wire::Bytes(f.raw.begin(), f.raw.end()), s, o);
              }),
        inner_(devices::CreateDevice("dmc16", profile, s, sink_)) {
    RelayLineSwitchesOf(*inner_);
  }
  std::string_view Model() const override { return "dmc16-broken"; }
  devices::DeviceLine Line() const override { return inner_->Line(); }
  void PowerOn() override { inner_->PowerOn(); }
  void PowerOff() override { inner_->PowerOff(); }
  bool Powered() const override { return inner_->Powered(); }
  void OnHostBytes(wire::ByteView bytes) override {
    if (!in_) {
      inner_->OnHostBytes(bytes);
      return;
    }
    const wire::Bytes changed = in_(bytes);
    inner_->OnHostBytes(changed);
  }
  void OnHostLink(bool open) override { inner_->OnHostLink(open); }
  // The control channel reaches the real device (e-stop, limit switches, inputs).
  sim::Rig* rig() override { return inner_->rig(); }
  sim::GioPort* gio() override { return inner_->gio(); }
  // The runner reads the real device's outputs (DMX, camera lines).
  const sim::DmxUniverse* dmx_out() const override { return inner_->dmx_out(); }
  const sim::CameraPort* camera_out() const override { return inner_->camera_out(); }

 private:
  InputBreakage in_;
  devices::FaultySink sink_;  // hands each frame the device writes to the breakage
  std::unique_ptr<devices::Device> inner_;
};

// Re-encodes `f` with a new ID or data.
inline wire::Bytes Reencode(const dmc::FrameRef& f, uint32_t id, wire::ByteView data) {
  wire::Bytes out;
  dmc::EncodeFrame(id, f.type, data, out);
  return out;
}

inline void PassThrough(const dmc::FrameRef&, wire::Bytes raw, sim::Scheduler&,
                        devices::ByteSink& out) {
  out.Write(raw);
}

}  // namespace moco::conformance::dmc_testing

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_BROKEN_DEVICE_H_
