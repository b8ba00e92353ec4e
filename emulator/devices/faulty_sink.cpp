// The wire-fault decorator of a device's output (see faulty_sink.h).
#include "devices/faulty_sink.h"

#include <algorithm>
#include <memory>
#include <utility>
#include <variant>

namespace moco::devices {

FaultySink::FaultySink(ByteSink& out, Fault fault, Framing framing)
    : out_(out), fault_(std::move(fault)), framing_(framing) {
  if (framing_ == Framing::kDmcFrames) decoder_ = std::make_unique<dmc::FrameDecoder>();
}

FaultySink::FaultySink(ByteSink& out, DmcFault fault)
    : out_(out),
      dmc_fault_(std::move(fault)),
      framing_(Framing::kDmcFrames),
      decoder_(std::make_unique<dmc::FrameDecoder>()) {}

void FaultySink::Write(wire::ByteView bytes) {
  if (framing_ == Framing::kWrites) {
    fault_(bytes, out_);
    return;
  }
  decoder_->Feed(bytes, [&](const dmc::FrameEvent& e) {
    const auto* f = std::get_if<dmc::FrameRef>(&e);
    if (f == nullptr) return;  // noise or a damaged frame: not the device's own output
    if (dmc_fault_) {
      dmc_fault_(*f, out_);
    } else {
      fault_(f->raw, out_);
    }
  });
}

FaultySink::Fault FaultySink::PassThrough() {
  return [](wire::ByteView message, ByteSink& out) { out.Write(message); };
}

FaultySink::Fault FaultySink::CutInto(std::vector<size_t> sizes) {
  auto next = std::make_shared<size_t>(0);
  return [sizes = std::move(sizes), next](wire::ByteView message, ByteSink& out) {
    size_t at = 0;
    while (at < message.size()) {
      const size_t n = sizes.empty() ? message.size() : sizes[(*next)++ % sizes.size()];
      const size_t len = std::min(n, message.size() - at);
      out.Write(message.subspan(at, len));
      at += len;
    }
  };
}

}  // namespace moco::devices
