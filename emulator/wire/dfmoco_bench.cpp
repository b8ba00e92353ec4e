// Benchmarks for the DFMoco ASCII codec (dfmoco-protocol.txt "Messages"): framing plus
// parsing of a Dragonframe-like host stream, and formatting of device replies.
// Reports lines/s (items_per_second) and bytes/s.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <string>
#include <vector>

#include "wire/dfmoco.h"

namespace moco::dfmoco {
namespace {

// A host session as Dragonframe drives a 4-motor rig: mostly `ms` polls while motors
// move, position queries and moves, the odd jog, pulse rate and go-motion frame.
std::string HostStream(size_t min_bytes, size_t& lines) {
  std::string s;
  lines = 0;
  int32_t pos = 0;
  while (s.size() < min_bytes) {
    pos += 1237;
    const int32_t m = (pos / 1237) % 4 + 1;
    std::vector<HostCommand> batch = {
        MoveMotor{m, pos},
        MotorStatusQuery{},
        MotorStatusQuery{},
        MotorStatusQuery{},
        PositionQuery{m},
        MotorStatusQuery{},
        JogMotor{m, -pos, 7500},
        MotorStatusQuery{},
        SetPulseRate{m, 5000},
        BlurFrame{1000,
                  500,
                  {BlurChannel{1, pos - 100, pos, pos + 100}, BlurChannel{2, -pos, 0, pos},
                   BlurChannel{3, 0, 10, 20}, BlurChannel{4, 5, 5, 5}}},
        MotorStatusQuery{},
        Go{},
    };
    for (const auto& c : batch) {
      AppendHost(c, s);
      ++lines;
    }
  }
  return s;
}

void DfmocoFrameAndParseHostStream(benchmark::State& state) {
  size_t lines = 0;
  const std::string stream = HostStream(64 * 1024, lines);
  const Dialect dialect = Dfmoco2(4);
  const auto mode = static_cast<LineTermination>(state.range(0));
  for (auto _ : state) {
    LineFramer framer({mode, kMaxLineBytes});
    size_t ok = 0;
    framer.Feed(stream, [&](const FrameEvent& e) {
      const auto r = ParseHostLine(e.text, dialect);
      ok += r.ok() ? 1 : 0;
    });
    benchmark::DoNotOptimize(ok);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * lines));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * stream.size()));
  state.SetLabel(mode == LineTermination::kSketch ? "sketch framing" : "lenient framing");
}
BENCHMARK(DfmocoFrameAndParseHostStream)
    ->Arg(static_cast<int>(LineTermination::kSketch))
    ->Arg(static_cast<int>(LineTermination::kLenient));

void DfmocoFrameOnly(benchmark::State& state) {
  size_t lines = 0;
  const std::string stream = HostStream(64 * 1024, lines);
  for (auto _ : state) {
    LineFramer framer;
    size_t n = 0;
    framer.Feed(stream, [&](const FrameEvent& e) { n += e.text.size(); });
    benchmark::DoNotOptimize(n);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * lines));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * stream.size()));
}
BENCHMARK(DfmocoFrameOnly);

std::vector<DeviceReply> Replies() {
  std::vector<DeviceReply> r;
  for (int32_t i = 0; i < 256; ++i) {
    const int32_t m = i % 4 + 1;
    r.push_back(MotorStatusReply{{i % 2 == 0, false, i % 3 == 0, false}});
    r.push_back(PositionReply{m, i * 10007 - 1000000});
    r.push_back(MoveReply{m, i * 313});
    r.push_back(MotorStatusReply{{false, false, false, false}});
    r.push_back(JogReply{m});
    r.push_back(PulseRateReply{m, 20000});
    r.push_back(BlurReply{1000});
    r.push_back(GoReply{});
  }
  r.push_back(HelloReply{2, 4, "2.0.0"});
  return r;
}

void DfmocoFormatReplies(benchmark::State& state) {
  const std::vector<DeviceReply> replies = Replies();
  std::string out;
  size_t bytes = 0;
  for (auto _ : state) {
    out.clear();
    for (const auto& r : replies) AppendDevice(r, out);
    bytes += out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * replies.size()));
  state.SetBytesProcessed(static_cast<int64_t>(bytes));
}
BENCHMARK(DfmocoFormatReplies);

void DfmocoParseDeviceReplies(benchmark::State& state) {
  std::string stream;
  const std::vector<DeviceReply> replies = Replies();
  for (const auto& r : replies) AppendDevice(r, stream);
  const Dialect dialect = Dfmoco2(4);
  for (auto _ : state) {
    LineFramer framer;
    size_t ok = 0;
    framer.Feed(stream, [&](const FrameEvent& e) { ok += ParseDeviceLine(e.text, dialect).ok(); });
    benchmark::DoNotOptimize(ok);
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * replies.size()));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * stream.size()));
}
BENCHMARK(DfmocoParseDeviceReplies);

}  // namespace
}  // namespace moco::dfmoco
