// A ByteSink between a device and its link that plants wire faults, for
// tests of hosts and conformance runners against broken devices: the
// device's output is cut into messages (each Write, or each DMC v2 frame,
// dmc-v2-protocol.txt "Frame format") and a fault decides what becomes of
// each one: passed on, changed, dropped, repeated, delayed or cut into
// pieces. The device itself stays sound.
#ifndef MOCO_DEVICES_FAULTY_SINK_H_
#define MOCO_DEVICES_FAULTY_SINK_H_

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include "devices/device.h"
#include "wire/bytes.h"
#include "wire/dmc_frame.h"

namespace moco::devices {

class FaultySink final : public ByteSink {
 public:
  // How the device's output is cut into messages.
  enum class Framing : uint8_t {
    kWrites,     // each Write is one message
    kDmcFrames,  // each whole DMC v2 frame; bytes outside a valid frame are dropped
  };
  // What becomes of one message: writes what the broken device sends
  // instead to `out` (now or later), or nothing.
  using Fault = std::function<void(wire::ByteView message, ByteSink& out)>;
  // A fault on a DMC v2 frame, with the frame decoded (framing kDmcFrames).
  using DmcFault = std::function<void(const dmc::FrameRef& frame, ByteSink& out)>;

  // `out` must outlive the sink.
  FaultySink(ByteSink& out, Fault fault, Framing framing = Framing::kWrites);
  // Framing kDmcFrames, `fault` on each frame.
  FaultySink(ByteSink& out, DmcFault fault);

  void Write(wire::ByteView bytes) override;
  bool HostBytesWaiting() override { return out_.HostBytesWaiting(); }

  // Every message unchanged.
  static Fault PassThrough();
  // Every message written in pieces of `sizes` bytes, round robin across
  // messages (empty: whole). REQUIRES: every size > 0.
  static Fault CutInto(std::vector<size_t> sizes);

 private:
  ByteSink& out_;
  Fault fault_;
  DmcFault dmc_fault_;
  Framing framing_;
  std::unique_ptr<dmc::FrameDecoder> decoder_;  // kDmcFrames
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_FAULTY_SINK_H_
