// The wire-fault decorator: messages cut by writes or by DMC v2 frames
// (dmc-v2-protocol.txt "Frame format"), whatever the chunking of the
// device's writes; pieces round robin; faults that drop, change or repeat.
#include "devices/faulty_sink.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "devices/test_support.h"
#include "sim/scheduler.h"
#include "wire/dmc.h"

namespace moco::devices {
namespace {

using testing::RecordingSink;

wire::ByteView View(const std::string& s) {
  return wire::ByteView(reinterpret_cast<const uint8_t*>(s.data()), s.size());
}

std::vector<std::string> Texts(const RecordingSink& r) {
  std::vector<std::string> v;
  for (const RecordingSink::Chunk& c : r.chunks) v.push_back(c.bytes);
  return v;
}

TEST(FaultySink, PassThroughHandsOnEachWriteAsItIs) {
  sim::Scheduler s;
  RecordingSink rec(s);
  FaultySink sink(rec, FaultySink::PassThrough());
  sink.Write(View("hi 1.2\r\n"));
  sink.Write(View("ms 1 0\r\n"));
  EXPECT_EQ(Texts(rec), (std::vector<std::string>{"hi 1.2\r\n", "ms 1 0\r\n"}));
}

TEST(FaultySink, CutIntoWritesPiecesRoundRobinAcrossWrites) {
  sim::Scheduler s;
  RecordingSink rec(s);
  FaultySink sink(rec, FaultySink::CutInto({1, 3}));
  sink.Write(View("abcde"));
  sink.Write(View("fgh"));
  // 1, 3, 1 of the first write (cut at its end), then 3 of the second.
  EXPECT_EQ(Texts(rec), (std::vector<std::string>{"a", "bcd", "e", "fgh"}));
  EXPECT_EQ(rec.All(), "abcdefgh");

  RecordingSink whole(s);
  FaultySink uncut(whole, FaultySink::CutInto({}));
  uncut.Write(View("abcde"));
  EXPECT_EQ(Texts(whole), (std::vector<std::string>{"abcde"}));
}

TEST(FaultySink, DmcFramesAreWholeWhateverTheChunkingAndNoiseIsDropped) {
  sim::Scheduler s;
  RecordingSink rec(s);
  std::vector<dmc::Frame> seen;
  FaultySink sink(rec, [&](const dmc::FrameRef& f, ByteSink& out) {
    seen.push_back(f.ToFrame());
    if (f.type == dmc::ToWire(dmc::MsgType::kMotorStatus)) return;  // dropped
    out.Write(f.raw);
    if (f.type == dmc::ToWire(dmc::MsgType::kGioIn)) out.Write(f.raw);  // sent twice
  });
  wire::Bytes stream = {0x00, 0x13};  // noise before the first frame
  const wire::Bytes status = dmc::Encode(7, dmc::MotorStatusResponse{0x3, 0});
  const wire::Bytes gio = dmc::Encode(8, dmc::GioInReport{0x5});
  stream.insert(stream.end(), status.begin(), status.end());
  stream.insert(stream.end(), gio.begin(), gio.end());
  for (size_t at = 0; at < stream.size(); at += 3) {
    sink.Write(wire::ByteView(stream).subspan(at, std::min<size_t>(3, stream.size() - at)));
  }
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_EQ(seen[0].id, 7u);
  EXPECT_EQ(seen[0].type, dmc::ToWire(dmc::MsgType::kMotorStatus));
  EXPECT_EQ(seen[1].id, 8u);
  const std::string g(gio.begin(), gio.end());
  EXPECT_EQ(Texts(rec), (std::vector<std::string>{g, g}));
}

TEST(FaultySink, AFaultOnBytesSeesEachDmcFrameWhole) {
  sim::Scheduler s;
  RecordingSink rec(s);
  FaultySink sink(
      rec,
      [](wire::ByteView frame, ByteSink& out) {
        wire::Bytes b(frame.begin(), frame.end());
        b.back() = static_cast<uint8_t>(b.back() + 1);  // a bad checksum
        out.Write(b);
      },
      FaultySink::Framing::kDmcFrames);
  const wire::Bytes hi = dmc::Encode(1, dmc::GioInReport{0x1});
  sink.Write(wire::ByteView(hi).first(4));
  EXPECT_TRUE(rec.chunks.empty()) << "half a frame is held";
  sink.Write(wire::ByteView(hi).subspan(4));
  ASSERT_EQ(rec.chunks.size(), 1u);
  wire::Bytes want = hi;
  want.back() = static_cast<uint8_t>(want.back() + 1);
  EXPECT_EQ(rec.bytes(), want);
  EXPECT_FALSE(dmc::DecodeFrame(rec.bytes()).ok());
}

}  // namespace
}  // namespace moco::devices
