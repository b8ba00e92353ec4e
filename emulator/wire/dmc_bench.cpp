// Throughput of the DMC v2 codec (dmc-v2-protocol.txt "Message Format"): the
// stream decoder, typed message decode and encode over a mixed, realistic
// stream of position updates, status replies, ACKs and upload axis chunks.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "wire/dmc.h"

namespace moco::dmc {
namespace {

// One round of traffic as during an upload with a live device: an axis chunk
// of 250 positions (1005 data bytes), position updates for 16 motors, motor
// status replies and ACKs.
struct Traffic {
  std::vector<HostMessage> host;
  std::vector<DeviceMessage> device;
};

Traffic MakeTraffic() {
  Traffic t;
  RtUploadMoveAxis axis;
  axis.motor = 3;
  axis.start_index = 250;
  for (int i = 0; i < 250; ++i) axis.positions_steps.push_back(i * 37 - 4000);
  t.host.push_back(axis);
  t.host.push_back(MotorStatusRequest{});
  t.host.push_back(MotorMove{2, -120000});
  for (int i = 0; i < 10; ++i) {
    MotorPositionReport pos;
    pos.move_time_x1000 = static_cast<uint32_t>(i * 1000);
    for (int m = 0; m < 16; ++m) pos.positions_steps.push_back(m * 1000 + i);
    t.device.push_back(pos);
  }
  for (int i = 0; i < 5; ++i) t.device.push_back(MotorStatusResponse{0x5u, 0});
  for (int i = 0; i < 10; ++i) t.device.push_back(Ack{0x0101, ToWire(AckCode::kOk)});
  t.device.push_back(MotorMoveResponse{1});
  return t;
}

// The traffic encoded repeatedly to about `target` bytes.
Bytes MakeStream(size_t target, size_t* frames) {
  const Traffic t = MakeTraffic();
  Bytes out;
  uint32_t id = 0;
  *frames = 0;
  while (out.size() < target) {
    for (const auto& m : t.host) Encode(++id, m, out);
    for (const auto& m : t.device) Encode(++id, m, out);
    *frames += t.host.size() + t.device.size();
  }
  return out;
}

void DmcFrameDecode(benchmark::State& state) {
  size_t frames_per_stream = 0;
  const Bytes stream = MakeStream(1 << 20, &frames_per_stream);
  const size_t chunk = static_cast<size_t>(state.range(0));
  FrameDecoder dec;
  size_t frames = 0;
  for (auto _ : state) {
    for (size_t pos = 0; pos < stream.size(); pos += chunk) {
      const size_t n = std::min(chunk, stream.size() - pos);
      dec.Feed(ByteView(stream.data() + pos, n), [&frames](const FrameEvent& e) {
        frames += std::holds_alternative<FrameRef>(e) ? 1 : 0;
      });
    }
  }
  if (frames != frames_per_stream * state.iterations()) state.SkipWithError("lost frames");
  state.SetBytesProcessed(static_cast<int64_t>(stream.size()) * state.iterations());
  state.counters["frames"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}
BENCHMARK(DmcFrameDecode)->Arg(64)->Arg(4096)->Arg(1 << 20);

// Framing plus typed decode of every frame (host layouts for the host's
// types, device layouts for the rest).
void DmcMessageDecode(benchmark::State& state) {
  size_t frames_per_stream = 0;
  const Bytes stream = MakeStream(1 << 20, &frames_per_stream);
  FrameDecoder dec;
  size_t decoded = 0;
  for (auto _ : state) {
    for (size_t pos = 0; pos < stream.size(); pos += 4096) {
      const size_t n = std::min<size_t>(4096, stream.size() - pos);
      dec.Feed(ByteView(stream.data() + pos, n), [&decoded](const FrameEvent& e) {
        const auto* f = std::get_if<FrameRef>(&e);
        if (f == nullptr) return;
        const bool from_host = f->type == ToWire(MsgType::kRtUploadMoveAxis) ||
                               (f->type == ToWire(MsgType::kMotorStatus) && f->data.empty()) ||
                               (f->type == ToWire(MsgType::kMotorMove) && f->data.size() == 5);
        if (from_host) {
          auto m = DecodeHostMessage(f->type, f->data);
          decoded += m.ok() ? 1 : 0;
          benchmark::DoNotOptimize(m);
        } else {
          auto m = DecodeDeviceMessage(f->type, f->data);
          decoded += m.ok() ? 1 : 0;
          benchmark::DoNotOptimize(m);
        }
      });
    }
  }
  if (decoded != frames_per_stream * state.iterations()) state.SkipWithError("decode failed");
  state.SetBytesProcessed(static_cast<int64_t>(stream.size()) * state.iterations());
  state.counters["frames"] =
      benchmark::Counter(static_cast<double>(decoded), benchmark::Counter::kIsRate);
}
BENCHMARK(DmcMessageDecode);

void DmcEncode(benchmark::State& state) {
  const Traffic t = MakeTraffic();
  Bytes out;
  out.reserve(1 << 16);
  size_t bytes = 0;
  size_t frames = 0;
  uint32_t id = 0;
  for (auto _ : state) {
    out.clear();
    for (const auto& m : t.host) Encode(++id, m, out);
    for (const auto& m : t.device) Encode(++id, m, out);
    benchmark::DoNotOptimize(out.data());
    bytes += out.size();
    frames += t.host.size() + t.device.size();
  }
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
  state.counters["frames"] =
      benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}
BENCHMARK(DmcEncode);

void DmcFletcher16(benchmark::State& state) {
  const Bytes data(static_cast<size_t>(state.range(0)), 0xa5);
  for (auto _ : state) benchmark::DoNotOptimize(Fletcher16(data));
  state.SetBytesProcessed(static_cast<int64_t>(data.size()) * state.iterations());
}
BENCHMARK(DmcFletcher16)->Arg(1048);

}  // namespace
}  // namespace moco::dmc
