// Throughput of the StackShot binary codec (stackshot-protocol.txt section 2)
// on a realistic session: a host that polls CC_RAIL_STATUS every 100 ms
// (FACTS.md), reads the position every second, pings every 2 s, moves and
// fires the shutter every 5 s, after reading its configuration at start-up.
#include <benchmark/benchmark.h>

#include "wire/stackshot.h"

namespace moco::stackshot {
namespace {

struct Session {
  std::vector<HostCommand> commands;
  std::vector<DeviceReply> replies;
  Bytes host_stream;
  Bytes device_stream;
};

HostCommand Read(Command c, Payload p = Empty{}) {
  return HostCommand{Id(c), Action::kRead, kAxisX, false, false, std::move(p)};
}
HostCommand Write(Command c, Payload p) {
  return HostCommand{Id(c), Action::kWrite, kAxisX, false, false, std::move(p)};
}
DeviceReply Answer(Command c, Payload p) {
  return DeviceReply{Id(c), Action::kRspOk,           kAxisX,      false,
                     false, ReplyKind::kReadResponse, std::move(p)};
}
DeviceReply Ack(Command c) {
  return DeviceReply{Id(c), Action::kRspOk, kAxisX, false, false, ReplyKind::kWriteAck, Empty{}};
}

// A 10-minute session.
Session MakeSession() {
  Session s;
  auto add = [&s](HostCommand c, DeviceReply r) {
    s.commands.push_back(std::move(c));
    s.replies.push_back(std::move(r));
  };
  add(Read(Command::kSoftwareString), Answer(Command::kSoftwareString, Text{"1.0.7"}));
  add(Read(Command::kSerialNumber), Answer(Command::kSerialNumber, U32Value{1234}));
  add(Read(Command::kRailConfigName), Answer(Command::kRailConfigName, Text{"Macro"}));
  add(Read(Command::kRailConfigSpeed, UnitsQuery{Units::kSteps}),
      Answer(Command::kRailConfigSpeed, UnitsF32{Units::kSteps, 2000.0f}));
  add(Read(Command::kRailConfigRampTime), Answer(Command::kRailConfigRampTime, F32Value{0.3f}));
  add(Read(Command::kRailConfigBacklash, UnitsQuery{Units::kSteps}),
      Answer(Command::kRailConfigBacklash, UnitsF32{Units::kSteps, 40.0f}));
  add(Read(Command::kRailConfigDistancePerRev, UnitsQuery{}),
      Answer(Command::kRailConfigDistancePerRev, UnitsF32{Units::kMm, 2.0f}));
  float position_mm = 0.0f;
  for (int tick = 0; tick < 6000; ++tick) {  // 100 ms ticks
    const bool moving = tick % 50 < 10;
    add(Read(Command::kRailStatus),
        Answer(Command::kRailStatus, RailStatus{moving ? kRailStatusMoving : kRailStatusIdle}));
    if (tick % 10 == 0) {
      add(Read(Command::kRailPositionCurrent, UnitsQuery{Units::kMm}),
          Answer(Command::kRailPositionCurrent, UnitsF32{Units::kMm, position_mm}));
    }
    if (tick % 20 == 5) {
      add(Read(Command::kPing, PingRequest{static_cast<uint8_t>(tick)}),
          Answer(Command::kPing, PingAnswer(static_cast<uint8_t>(tick))));
    }
    if (tick % 50 == 0) {
      add(Write(Command::kRailMove, RailMove{Direction::kForward, Units::kMm, true, 0.05f}),
          Ack(Command::kRailMove));
      add(Write(Command::kRailShutterFire, ShutterFire{1, 0.25f, 0.5f}),
          Ack(Command::kRailShutterFire));
      position_mm += 0.05f;
    }
  }
  for (const auto& c : s.commands) EncodeHostCommand(c, s.host_stream);
  for (const auto& r : s.replies) EncodeDeviceReply(r, s.device_stream);
  return s;
}

const Session& TheSession() {
  static const Session s = MakeSession();
  return s;
}

constexpr size_t kChunkBytes = 64;  // a typical USB-serial read

void DecodeStream(benchmark::State& state, bool from_device) {
  const Session& s = TheSession();
  const Bytes& stream = from_device ? s.device_stream : s.host_stream;
  std::vector<DecodedPacket> packets;
  packets.reserve(s.commands.size());
  size_t decoded = 0;
  for (auto _ : state) {
    PacketDecoder decoder(from_device);
    packets.clear();
    for (size_t pos = 0; pos < stream.size(); pos += kChunkBytes) {
      decoder.Feed(ByteView(stream).subspan(pos, std::min(kChunkBytes, stream.size() - pos)),
                   packets);
    }
    for (const auto& d : packets) {
      if (from_device) {
        auto r = DecodeDevicePacket(d.packet);
        decoded += r.ok();
        benchmark::DoNotOptimize(r);
      } else {
        auto c = DecodeHostPacket(d.packet);
        decoded += c.ok();
        benchmark::DoNotOptimize(c);
      }
    }
  }
  if (decoded != packets.size() * static_cast<size_t>(state.iterations())) {
    state.SkipWithError("a packet of the session failed to decode");
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(packets.size()));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(stream.size()));
}

void EncodeStream(benchmark::State& state, bool from_device) {
  const Session& s = TheSession();
  Bytes out;
  out.reserve(std::max(s.host_stream.size(), s.device_stream.size()));
  for (auto _ : state) {
    out.clear();
    if (from_device) {
      for (const auto& r : s.replies) EncodeDeviceReply(r, out);
    } else {
      for (const auto& c : s.commands) EncodeHostCommand(c, out);
    }
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(s.commands.size()));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(from_device
                                                                        ? s.device_stream.size()
                                                                        : s.host_stream.size()));
}

void StackshotDecodeHostStream(benchmark::State& state) { DecodeStream(state, false); }
void StackshotDecodeDeviceStream(benchmark::State& state) { DecodeStream(state, true); }
void StackshotEncodeHostStream(benchmark::State& state) { EncodeStream(state, false); }
void StackshotEncodeDeviceStream(benchmark::State& state) { EncodeStream(state, true); }

// Framing alone: the streaming decoder without typed decode.
void StackshotFrameDeviceStream(benchmark::State& state) {
  const Bytes& stream = TheSession().device_stream;
  std::vector<DecodedPacket> packets;
  for (auto _ : state) {
    PacketDecoder decoder(true);
    packets.clear();
    decoder.Feed(stream, packets);
    benchmark::DoNotOptimize(packets.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(packets.size()));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(stream.size()));
}

BENCHMARK(StackshotDecodeHostStream);
BENCHMARK(StackshotDecodeDeviceStream);
BENCHMARK(StackshotEncodeHostStream);
BENCHMARK(StackshotEncodeDeviceStream);
BENCHMARK(StackshotFrameDeviceStream);

}  // namespace
}  // namespace moco::stackshot
