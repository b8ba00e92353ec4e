// Tests of DMC v2 framing against dmc-v2-protocol.txt "Message Format" and
// "Computing and Validating the Checksum" (ERRATA dmc 1.1, 1.2): the spec's own
// checksum routine as an oracle, frame layout, and the stream decoder's laws
// (any chunking, resync after noise, bit flips, oversize lengths).
#include "wire/dmc_frame.h"

#include <gtest/gtest.h>
#include <rapidcheck.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

namespace moco::dmc {

// The spec's example C code, copied verbatim but for the typedefs it assumes,
// a const on the input and the buffer type of the check-byte lines. Shared
// with dmc_test.cpp as an independent oracle. The spec's code narrows ints
// implicitly, so -Wconversion is off for it alone.
namespace spec_oracle {

typedef uint16_t alt_u16;
typedef uint8_t alt_u8;

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wconversion"
// clang-format off

uint16_t computeChecksum(const uint8_t * data, int bytes)
{
    alt_u16 sum1 = 0, sum2 = 0;
    size_t tlen;

    while (bytes)
    {
        tlen = ((bytes >= 20) ? 20 : bytes);
        bytes -= tlen;
        do
        {
            sum2 += sum1 += *data++;
            tlen--;
        } while (tlen);
        sum1 %= 0xff;
        sum2 %= 0xff;
    }
    return (sum2 << 8) | sum1;
}

// The spec's check-byte lines, appending to the message buffer.
void AppendCheckBytes(std::vector<uint8_t>& messageBuffer) {
  int messageLength = static_cast<int>(messageBuffer.size());
  alt_u16 csum = computeChecksum(messageBuffer.data(), messageLength);
  alt_u8 c0, c1, f0, f1;
  f0 = csum & 0xff;
  f1 = (csum >> 8) & 0xff;
  c0 = 0xff - ((f0 + f1) % 0xff);
  c1 = 0xff - ((f0 + c0) % 0xff);
  messageBuffer.push_back(c0);
  messageBuffer.push_back(c1);
}

// clang-format on
#pragma GCC diagnostic pop

}  // namespace spec_oracle

namespace {

using wire::FromHex;
using wire::ToHex;

// A frame built field by field from the spec's header table, independently of
// EncodeFrame: 'D' 'F', ID u32 LE, Type u16 LE, Length u16 LE, Data, check bytes.
Bytes OracleFrame(uint32_t id, uint16_t type, const Bytes& data) {
  Bytes f = {'D', 'F'};
  for (int i = 0; i < 4; ++i) f.push_back(static_cast<uint8_t>(id >> (8 * i)));
  f.push_back(static_cast<uint8_t>(type));
  f.push_back(static_cast<uint8_t>(type >> 8));
  f.push_back(static_cast<uint8_t>(data.size()));
  f.push_back(static_cast<uint8_t>(data.size() >> 8));
  f.insert(f.end(), data.begin(), data.end());
  spec_oracle::AppendCheckBytes(f);
  return f;
}

std::vector<Frame> GoodFrames(const std::vector<StreamEvent>& events) {
  std::vector<Frame> out;
  for (const auto& e : events) {
    if (const auto* f = std::get_if<Frame>(&e)) out.push_back(*f);
  }
  return out;
}

size_t SkippedTotal(const std::vector<StreamEvent>& events) {
  size_t n = 0;
  for (const auto& e : events) {
    if (const auto* f = std::get_if<FramingError>(&e)) {
      if (f->kind == FramingError::Kind::kSkipped) n += f->bytes;
    }
  }
  return n;
}

// Feeds `stream` cut at the given sizes (cycled), then Finish(); checks the
// buffer bound after every chunk.
std::vector<StreamEvent> DecodeChunked(const Bytes& stream, const std::vector<size_t>& cuts,
                                       size_t* max_pending = nullptr,
                                       FrameDecoderOptions options = {}) {
  std::vector<StreamEvent> events;
  FrameDecoder dec(options);
  auto collect = [&events](const FrameEvent& e) { events.push_back(ToStreamEvent(e)); };
  size_t pos = 0;
  size_t i = 0;
  size_t high = 0;
  while (pos < stream.size()) {
    size_t n = cuts.empty() ? stream.size() : std::max<size_t>(1, cuts[i++ % cuts.size()]);
    n = std::min(n, stream.size() - pos);
    dec.Feed(ByteView(stream.data() + pos, n), collect);
    high = std::max(high, dec.pending_bytes());
    pos += n;
  }
  dec.Finish(collect);
  if (max_pending != nullptr) *max_pending = high;
  return events;
}

// --- Generators ---------------------------------------------------------------

rc::Gen<Frame> GenFrame(size_t max_data = 64) {
  return rc::gen::build<Frame>(
      rc::gen::set(&Frame::id), rc::gen::set(&Frame::type),
      rc::gen::set(&Frame::data,
                   rc::gen::mapcat(rc::gen::inRange<size_t>(0, max_data + 1), [](size_t n) {
                     return rc::gen::container<Bytes>(n, rc::gen::arbitrary<uint8_t>());
                   })));
}

// Noise biased towards the marker bytes so that false "DF" starts are common.
rc::Gen<Bytes> GenNoise(size_t max_len = 40) {
  return rc::gen::mapcat(rc::gen::inRange<size_t>(0, max_len + 1), [](size_t n) {
    return rc::gen::container<Bytes>(
        n, rc::gen::weightedOneOf<uint8_t>({{3, rc::gen::arbitrary<uint8_t>()},
                                            {1, rc::gen::just<uint8_t>('D')},
                                            {1, rc::gen::just<uint8_t>('F')}}));
  });
}

// A stream of good frames, noise, corrupted frames and oversize headers.
rc::Gen<Bytes> GenStream() {
  auto segment = rc::gen::oneOf(
      rc::gen::map(GenFrame(), [](const Frame& f) { return EncodeFrame(f); }), GenNoise(),
      rc::gen::map(rc::gen::pair(GenFrame(), rc::gen::arbitrary<uint32_t>()),
                   [](const std::pair<Frame, uint32_t>& p) {
                     Bytes b = EncodeFrame(p.first);
                     b[p.second % b.size()] ^= static_cast<uint8_t>(1u << (p.second >> 29));
                     return b;
                   }),
      rc::gen::map(rc::gen::inRange<uint32_t>(kMaxDataLength + 1, 0x10000), [](uint32_t len) {
        Bytes b = {'D', 'F', 1, 2, 3, 4, 0x31, 0x00};
        b.push_back(static_cast<uint8_t>(len));
        b.push_back(static_cast<uint8_t>(len >> 8));
        return b;
      }));
  return rc::gen::map(rc::gen::container<std::vector<Bytes>>(segment),
                      [](const std::vector<Bytes>& parts) {
                        Bytes s;
                        for (const Bytes& p : parts) s.insert(s.end(), p.begin(), p.end());
                        return s;
                      });
}

// --- Checksum ---------------------------------------------------------------------

TEST(DmcFrameDecoderTest, EmptyChunksChangeNothing) {
  const Bytes frame = EncodeFrame(Frame{7, 0x0001, {}});
  FrameDecoder d;
  int frames = 0;
  auto count = [&](const FrameEvent& e) { frames += std::holds_alternative<FrameRef>(e) ? 1 : 0; };
  d.Feed(ByteView(), count);
  d.Feed(ByteView(frame.data(), 5), count);
  d.Feed(ByteView(), count);  // in the middle of a frame
  d.Feed(ByteView(frame.data() + 5, frame.size() - 5), count);
  d.Feed(ByteView(), count);
  EXPECT_EQ(frames, 1);
}

TEST(DmcChecksumTest, PublishedFletcher16Values) {
  // Fletcher-16 reference values for the strings the spec's cited article uses.
  auto f = [](const char* s) {
    return Fletcher16(ByteView(reinterpret_cast<const uint8_t*>(s), std::strlen(s)));
  };
  EXPECT_EQ(f("abcde"), 0xc8f0);
  EXPECT_EQ(f("abcdef"), 0x2057);
  EXPECT_EQ(f("abcdefgh"), 0x0627);
  EXPECT_EQ(f(""), 0);
}

RC_GTEST_PROP(DmcChecksumProp, MatchesSpecRoutine, (const std::vector<uint8_t>& bytes)) {
  RC_ASSERT(Fletcher16(bytes) ==
            spec_oracle::computeChecksum(bytes.data(), static_cast<int>(bytes.size())));
}

RC_GTEST_PROP(DmcChecksumProp, MatchesSpecRoutineOnLongInputs, ()) {
  // Past several 20-byte blocks, with runs of 0xff that push the sums highest.
  const auto bytes = *rc::gen::container<Bytes>(
      *rc::gen::inRange<size_t>(0, 3000),
      rc::gen::weightedOneOf<uint8_t>(
          {{1, rc::gen::arbitrary<uint8_t>()}, {3, rc::gen::just<uint8_t>(0xff)}}));
  RC_ASSERT(Fletcher16(bytes) ==
            spec_oracle::computeChecksum(bytes.data(), static_cast<int>(bytes.size())));
}

RC_GTEST_PROP(DmcChecksumProp, CheckBytesMatchSpecAndZeroTheSum,
              (const std::vector<uint8_t>& message)) {
  Bytes with_oracle = message;
  spec_oracle::AppendCheckBytes(with_oracle);
  const auto check = CheckBytes(Fletcher16(message));
  RC_ASSERT(check[0] == with_oracle[with_oracle.size() - 2]);
  RC_ASSERT(check[1] == with_oracle[with_oracle.size() - 1]);
  RC_ASSERT(
      spec_oracle::computeChecksum(with_oracle.data(), static_cast<int>(with_oracle.size())) == 0);
}

// --- Frame encode / decode -----------------------------------------------------------

TEST(DmcFrameTest, EncodesHeaderFieldsLittleEndian) {
  // MSG_HI request, ID 1: 'D' 'F', 01 00 00 00, 01 00, 00 00, check bytes.
  const Bytes f = EncodeFrame(Frame{1, 0x0001, {}});
  EXPECT_EQ(ToHex(f), "44460100000001000000442f");
  const Bytes g = EncodeFrame(Frame{0x04030201, 0x8031, {0x10, 0x00}});
  EXPECT_EQ(ToHex(ByteView(g).first(10)), "44460102030431800200");
  EXPECT_EQ(g, OracleFrame(0x04030201, 0x8031, {0x10, 0x00}));
}

RC_GTEST_PROP(DmcFrameProp, EncodeMatchesSpecLayoutAndDecodes, ()) {
  const Frame f = *GenFrame(kMaxDataLength);
  const Bytes bytes = EncodeFrame(f);
  RC_ASSERT(bytes == OracleFrame(f.id, f.type, f.data));
  const auto back = DecodeFrame(bytes);
  RC_ASSERT(back.ok());
  RC_ASSERT(*back == f);
}

TEST(DmcFrameTest, DecodeFrameErrors) {
  using Kind = DecodeError::Kind;
  const Bytes good = OracleFrame(7, 0x0031, {3, 0x50, 0xfb, 0xff, 0xff});

  auto short_frame = DecodeFrame(ByteView(good).first(11));
  ASSERT_FALSE(short_frame.ok());
  EXPECT_EQ(short_frame.error().kind, Kind::kTruncated);

  auto missing_check = DecodeFrame(ByteView(good).first(good.size() - 1));
  ASSERT_FALSE(missing_check.ok());
  EXPECT_EQ(missing_check.error().kind, Kind::kTruncated);

  Bytes bad_marker = good;
  bad_marker[1] = 'X';
  EXPECT_EQ(DecodeFrame(bad_marker).error().kind, Kind::kBadValue);

  Bytes trailing = good;
  trailing.push_back(0);
  auto t = DecodeFrame(trailing);
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.error().kind, Kind::kTrailing);
  EXPECT_EQ(t.error().offset, good.size());

  Bytes bad_sum = good;
  bad_sum[12] ^= 0x01;
  auto c = DecodeFrame(bad_sum);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().kind, Kind::kBadChecksum);

  // ERRATA 1.2: Length 1037 is a framing error even with the bytes present.
  Bytes big = OracleFrame(1, 0x0101, Bytes(1037, 0));
  auto b = DecodeFrame(big);
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(b.error().kind, Kind::kBadLength);
  EXPECT_EQ(b.error().offset, kLengthOffset);
  // 1036 is the largest accepted data section.
  EXPECT_TRUE(DecodeFrame(OracleFrame(1, 0x0101, Bytes(1036, 0x5a))).ok());
}

TEST(DmcFrameTest, ReferenceParserTypeMask) {
  EXPECT_TRUE(HasReferenceParserType(0x0001));
  EXPECT_TRUE(HasReferenceParserType(0x0207));
  EXPECT_TRUE(HasReferenceParserType(0x8207));
  EXPECT_TRUE(HasReferenceParserType(0x83ff));
  EXPECT_FALSE(HasReferenceParserType(0x0400));
  EXPECT_FALSE(HasReferenceParserType(0x4000));
  EXPECT_FALSE(HasReferenceParserType(0xffff));
}

// --- Stream decoder -----------------------------------------------------------------

TEST(DmcFrameDecoderTest, DeliversTypesOutsideReferenceMask) {
  const Bytes f = OracleFrame(9, 0x0400, {});
  const auto events = DecodeStream(f);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(std::get<Frame>(events[0]), (Frame{9, 0x0400, {}}));
}

TEST(DmcFrameDecoderTest, ChecksumErrorCarriesIdAndType) {
  Bytes f = OracleFrame(0x11223344, 0x0031, {3, 1, 0, 0, 0});
  f[11] ^= 0x40;  // a data byte
  Bytes stream = f;
  const Bytes next = OracleFrame(5, 0x0030, {});
  stream.insert(stream.end(), next.begin(), next.end());
  const auto events = DecodeStream(stream);
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(std::get<ChecksumError>(events[0]), (ChecksumError{0x11223344, 0x0031, 5}));
  // The bad frame's bytes are accounted as skipped, then the next frame.
  EXPECT_EQ(std::get<FramingError>(events[1]).kind, FramingError::Kind::kSkipped);
  EXPECT_EQ(std::get<FramingError>(events[1]).bytes, f.size());
  EXPECT_EQ(std::get<Frame>(events[2]), (Frame{5, 0x0030, {}}));
}

TEST(DmcFrameDecoderTest, OversizeLengthIsFramingErrorAndScanResumes) {
  Bytes stream = {'D', 'F', 1, 0, 0, 0, 0x01, 0x01, 0x0d, 0x04};  // Length 1037
  const Bytes good = OracleFrame(2, 0x0030, {});
  stream.insert(stream.end(), good.begin(), good.end());
  size_t high = 0;
  const auto events = DecodeChunked(stream, {1}, &high);
  ASSERT_EQ(events.size(), 3u);
  const auto& over = std::get<FramingError>(events[0]);
  EXPECT_EQ(over.kind, FramingError::Kind::kOversize);
  EXPECT_EQ(over.length, 1037);
  EXPECT_EQ(over.id, 1u);
  EXPECT_EQ(over.type, 0x0101);
  EXPECT_EQ(std::get<FramingError>(events[1]).bytes, 10u);
  EXPECT_EQ(std::get<Frame>(events[2]).id, 2u);
  // Fed byte by byte, nothing but the oversize header and then the 12-byte
  // frame's first 11 bytes were ever pending.
  EXPECT_EQ(high, good.size() - 1);
}

TEST(DmcFrameDecoderTest, FalseMarkerSwallowingARealFrameStillFindsIt) {
  // Noise "DF" with a plausible header whose Length covers the real frame.
  const Bytes real = OracleFrame(77, 0x0031, {1, 0x10, 0, 0, 0});
  Bytes stream = {0x00, 'D', 'F', 9, 9, 9, 9, 0x30, 0x00, 40, 0};
  stream.insert(stream.end(), real.begin(), real.end());
  // The real frame arrives before the false one's 40 + 2 bytes are complete;
  // later traffic completes it.
  const Bytes later = OracleFrame(78, 0x0030, {});
  for (int i = 0; i < 3; ++i) stream.insert(stream.end(), later.begin(), later.end());
  const auto frames = GoodFrames(DecodeStream(stream));
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames[0].id, 77u);
  EXPECT_EQ(frames[1].id, 78u);
}

TEST(DmcFrameDecoderTest, FinishGivesUpOnAnIncompleteFalseFrame) {
  // Idle line: the false frame will never complete; Finish() rescans.
  const Bytes real = OracleFrame(77, 0x0031, {1, 0x10, 0, 0, 0});
  Bytes stream = {'D', 'F', 9, 9, 9, 9, 0x30, 0x00, 0x00, 0x04};  // Length 1024
  stream.insert(stream.end(), real.begin(), real.end());
  std::vector<StreamEvent> events;
  FrameDecoder dec;
  auto collect = [&events](const FrameEvent& e) { events.push_back(ToStreamEvent(e)); };
  dec.Feed(stream, collect);
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(dec.pending_bytes(), stream.size());
  dec.Finish(collect);
  ASSERT_EQ(events.size(), 3u);
  const auto& trunc = std::get<FramingError>(events[0]);
  EXPECT_EQ(trunc.kind, FramingError::Kind::kTruncated);
  EXPECT_EQ(trunc.bytes, stream.size());
  EXPECT_EQ(trunc.length, 1024);
  EXPECT_EQ(std::get<FramingError>(events[1]).bytes, 10u);
  EXPECT_EQ(std::get<Frame>(events[2]).id, 77u);
  EXPECT_EQ(dec.pending_bytes(), 0u);
}

// Any receive buffer from the spec's minimum to the largest modelled, with
// or without rescanning rejected candidates.
rc::Gen<FrameDecoderOptions> GenOptions() {
  return rc::gen::build<FrameDecoderOptions>(
      rc::gen::set(&FrameDecoderOptions::max_frame_bytes,
                   rc::gen::oneOf(rc::gen::just(kMaxFrameSize), rc::gen::just(size_t{2048}),
                                  rc::gen::inRange(kMaxFrameSize, kLargestReceiveBuffer + 1))),
      rc::gen::set(&FrameDecoderOptions::rescan_rejected));
}

RC_GTEST_PROP(DmcFrameDecoderProp, AnyChunkingYieldsTheSameEvents, ()) {
  const Bytes stream = *GenStream();
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 80));
  const auto options = *GenOptions();
  const auto whole = DecodeChunked(stream, {}, nullptr, options);
  RC_ASSERT(DecodeChunked(stream, cuts, nullptr, options) == whole);
  RC_ASSERT(DecodeChunked(stream, {1}, nullptr, options) == whole);
}

RC_GTEST_PROP(DmcFrameDecoderProp, EveryByteIsInAGoodFrameOrSkipped, ()) {
  const Bytes stream = *GenStream();
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 80));
  const auto options = *GenOptions();
  size_t high = 0;
  const auto events = DecodeChunked(stream, cuts, &high, options);
  size_t framed = 0;
  for (const Frame& f : GoodFrames(events)) framed += kHeaderSize + f.data.size() + kCheckSize;
  RC_ASSERT(framed + SkippedTotal(events) == stream.size());
  RC_ASSERT(high < options.max_frame_bytes);
}

RC_GTEST_PROP(DmcFrameDecoderProp, StreamOfGoodFramesDecodesExactly, ()) {
  const auto frames = *rc::gen::container<std::vector<Frame>>(GenFrame());
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 80));
  Bytes stream;
  for (const Frame& f : frames) EncodeFrame(f, stream);
  const auto events = DecodeChunked(stream, cuts);
  RC_ASSERT(events.size() == frames.size());  // no errors, nothing skipped
  RC_ASSERT(GoodFrames(events) == frames);
}

RC_GTEST_PROP(DmcFrameDecoderProp, GarbagePrefixThenValidFrameYieldsIt, ()) {
  const Bytes garbage = *GenNoise(200);
  const Frame f = *GenFrame();
  Bytes stream = garbage;
  EncodeFrame(f, stream);
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 80));
  const auto frames = GoodFrames(DecodeChunked(stream, cuts));
  RC_ASSERT(!frames.empty());
  RC_ASSERT(frames.back() == f);
}

RC_GTEST_PROP(DmcFrameDecoderProp, GarbageWithoutMarkerIsOneSkipThenTheFrame, ()) {
  const auto garbage = *rc::gen::container<Bytes>(
      rc::gen::suchThat(rc::gen::arbitrary<uint8_t>(), [](uint8_t b) { return b != 'D'; }));
  const Frame f = *GenFrame();
  Bytes stream = garbage;
  EncodeFrame(f, stream);
  std::vector<StreamEvent> events;
  FrameDecoder dec;
  dec.Feed(stream, [&events](const FrameEvent& e) { events.push_back(ToStreamEvent(e)); });
  std::vector<StreamEvent> expected;
  if (!garbage.empty()) {
    FramingError skip;
    skip.bytes = garbage.size();
    expected.push_back(skip);
  }
  expected.push_back(f);
  RC_ASSERT(events == expected);
}

// Law for single-bit errors. A valid frame F is followed by a valid frame G
// (different ID). For every single-bit flip inside F:
//  (a) no good frame equal to F is reported (Fletcher-16 mod 255 changes sum1
//      by +-2^k != 0 mod 255 whenever the checked span is unchanged, and a
//      changed Length changes the data);
//  (b) a flip outside the marker and the Length field yields ChecksumError
//      with the header fields as received, before anything else but skips;
//  (c) a flip outside the Length field never loses G;
//  (d) a flip in the Length field loses G only if some other good frame was
//      reported: an enlarged Length can reach into G, and a span that by
//      coincidence sums to zero (about 1 in 65025) is then taken as a frame.
RC_GTEST_PROP(DmcFrameDecoderProp, EverySingleBitFlipIsDetected, ()) {
  const Frame f = *GenFrame(40);
  Frame g = *GenFrame(40);
  g.id = f.id + 1;
  const Bytes fb = EncodeFrame(f);
  const Bytes gb = EncodeFrame(g);
  for (size_t bit = 0; bit < fb.size() * 8; ++bit) {
    Bytes stream = fb;
    stream[bit / 8] ^= static_cast<uint8_t>(1u << (bit % 8));
    const size_t byte = bit / 8;
    stream.insert(stream.end(), gb.begin(), gb.end());
    const auto events = DecodeStream(stream);
    const auto frames = GoodFrames(events);
    RC_ASSERT(std::find(frames.begin(), frames.end(), f) == frames.end());
    const bool in_marker = byte < kMarkerSize;
    const bool in_length = byte == kLengthOffset || byte == kLengthOffset + 1;
    const bool g_found = std::find(frames.begin(), frames.end(), g) != frames.end();
    if (!in_marker && !in_length) {
      const ChecksumError* first = nullptr;
      for (const auto& e : events) {
        if (const auto* fe = std::get_if<FramingError>(&e);
            fe != nullptr && fe->kind == FramingError::Kind::kSkipped) {
          continue;
        }
        first = std::get_if<ChecksumError>(&e);
        break;
      }
      RC_ASSERT(first != nullptr);
      uint32_t id = 0;
      for (int i = 0; i < 4; ++i) id |= static_cast<uint32_t>(stream[kIdOffset + i]) << (8 * i);
      RC_ASSERT(first->id == id);
      RC_ASSERT(first->type == static_cast<uint16_t>(stream[6] | (stream[7] << 8)));
      RC_ASSERT(first->length == f.data.size());
    }
    if (!in_length) {
      RC_ASSERT(g_found);
    } else {
      RC_ASSERT(g_found || !frames.empty());
    }
  }
}

RC_GTEST_PROP(DmcFrameDecoderProp, LengthAbove1036IsFramingErrorWithBoundedMemory, ()) {
  const auto length = *rc::gen::inRange<uint32_t>(kMaxDataLength + 1, 0x10000);
  const auto id = *rc::gen::arbitrary<uint32_t>();
  const auto type = *rc::gen::arbitrary<uint16_t>();
  // The oversize frame's "data" follows in full: none of it may be buffered.
  const auto filler = *rc::gen::container<Bytes>(
      *rc::gen::inRange<size_t>(0, 3000),
      rc::gen::suchThat(rc::gen::arbitrary<uint8_t>(), [](uint8_t b) { return b != 'D'; }));
  Bytes stream = OracleFrame(id, type, {});
  stream[kLengthOffset] = static_cast<uint8_t>(length);
  stream[kLengthOffset + 1] = static_cast<uint8_t>(length >> 8);
  stream.resize(kHeaderSize);
  stream.insert(stream.end(), filler.begin(), filler.end());
  const Frame after{5, 0x0034, {1, 2, 3, 4}};
  const size_t after_size = kHeaderSize + after.data.size() + kCheckSize;
  EncodeFrame(after, stream);
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 300));
  size_t high = 0;
  const auto events = DecodeChunked(stream, cuts, &high);
  // Only a header, or the start of the final 16-byte frame, is ever pending.
  RC_ASSERT(high <= std::max(kHeaderSize, after_size - 1));
  RC_ASSERT(!events.empty());
  const auto* over = std::get_if<FramingError>(&events[0]);
  RC_ASSERT(over != nullptr);
  RC_ASSERT(over->kind == FramingError::Kind::kOversize);
  RC_ASSERT(over->length == length);
  RC_ASSERT(over->id == id);
  RC_ASSERT(over->type == type);
  RC_ASSERT(GoodFrames(events) == std::vector<Frame>{after});
}

// A false "DF" in noise right before a real frame, declaring any Length up to
// 1036, with anything after the real frame: the real frame is still found.
RC_GTEST_PROP(DmcFrameDecoderProp, FalseMarkerBeforeRealFrameDoesNotLoseIt, ()) {
  const Bytes noise = *GenNoise();
  const auto fake_len = *rc::gen::inRange<uint32_t>(0, kMaxDataLength + 1);
  const auto fake_hdr = *rc::gen::container<Bytes>(6, rc::gen::arbitrary<uint8_t>());
  const Frame real = *GenFrame();
  const Bytes tail = *GenNoise(1100);
  Bytes stream = noise;
  const size_t fake_at = stream.size();
  stream.push_back('D');
  stream.push_back('F');
  stream.insert(stream.end(), fake_hdr.begin(), fake_hdr.end());
  stream.push_back(static_cast<uint8_t>(fake_len));
  stream.push_back(static_cast<uint8_t>(fake_len >> 8));
  EncodeFrame(real, stream);
  stream.insert(stream.end(), tail.begin(), tail.end());
  // Not the law's case: the "false" frame happens to be a valid frame.
  const size_t fake_size = kHeaderSize + fake_len + kCheckSize;
  // (RC_PRE decomposes its expression, so || would not short-circuit there.)
  const bool fake_is_invalid = fake_at + fake_size > stream.size() ||
                               !ChecksumIsZero(ByteView(stream.data() + fake_at, fake_size));
  RC_PRE(fake_is_invalid);
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(1, 80));
  const auto frames = GoodFrames(DecodeChunked(stream, cuts));
  RC_ASSERT(std::find(frames.begin(), frames.end(), real) != frames.end());
}

// "The receiving buffer on the device must be at least 1048 bytes": a larger
// one (FACTS: dmc-lite, 2048) takes whole a frame the minimum calls oversize.
TEST(DmcFrameDecoderTest, LargerReceiveBufferWaitsForALengthUpToIt) {
  const Bytes big = OracleFrame(3, 0x0101, Bytes(2000, 0x11));  // Length 2000, 2012 bytes
  FrameDecoderOptions two_k;
  two_k.max_frame_bytes = 2048;
  size_t high = 0;
  const auto events = DecodeChunked(big, {1}, &high, two_k);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(std::get<Frame>(events[0]).data.size(), 2000u);
  EXPECT_EQ(high, big.size() - 1);  // held in the fixed buffer, nothing allocated
  // The spec's minimum drops the header as oversize and never buffers the data.
  const auto minimum = DecodeChunked(big, {7}, &high);
  ASSERT_FALSE(minimum.empty());
  EXPECT_EQ(std::get<FramingError>(minimum[0]).kind, FramingError::Kind::kOversize);
  EXPECT_TRUE(GoodFrames(minimum).empty());
  EXPECT_LT(high, kMaxFrameSize);
  // 2048 holds Length 2036 at most.
  Bytes over = OracleFrame(4, 0x0101, Bytes(2037, 0x11));
  const auto too_big = DecodeChunked(over, {}, nullptr, two_k);
  ASSERT_FALSE(too_big.empty());
  EXPECT_EQ(std::get<FramingError>(too_big[0]).kind, FramingError::Kind::kOversize);
  EXPECT_EQ(std::get<FramingError>(too_big[0]).length, 2037);
  FrameDecoderOptions absurd;
  absurd.max_frame_bytes = 1u << 20;
  EXPECT_EQ(FrameDecoder(absurd).max_data_length(), kLargestReceiveBuffer - 12);
}

// FACTS (dmc-lite): bytes behind a false "DF" are dropped, not rescanned. The
// same stream as FalseMarkerSwallowingARealFrameStillFindsIt loses the frame
// the false header covered.
TEST(DmcFrameDecoderTest, WithoutRescanACandidateThatFailsItsCheckIsDroppedWhole) {
  const Bytes real = OracleFrame(77, 0x0031, {1, 0x10, 0, 0, 0});
  Bytes stream = {'D', 'F', 9, 9, 9, 9, 0x30, 0x00, 15, 0};  // Length 15: covers `real`
  stream.insert(stream.end(), real.begin(), real.end());
  const Bytes later = OracleFrame(78, 0x0030, {});
  stream.insert(stream.end(), later.begin(), later.end());
  FrameDecoderOptions drop;
  drop.rescan_rejected = false;
  for (const std::vector<size_t>& cuts : {std::vector<size_t>{}, {1}, {5}}) {
    const auto events = DecodeChunked(stream, cuts, nullptr, drop);
    ASSERT_EQ(events.size(), 3u);
    EXPECT_EQ(std::get<ChecksumError>(events[0]), (ChecksumError{0x09090909, 0x0030, 15}));
    EXPECT_EQ(std::get<FramingError>(events[1]).bytes, 27u);  // the whole candidate
    EXPECT_EQ(std::get<Frame>(events[2]).id, 78u);
  }
  // With rescan (the spec's reading here) the covered frame is found.
  const auto frames = GoodFrames(DecodeStream(stream));
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].id, 77u);
}

TEST(DmcFrameDecoderTest, WithoutRescanAnOversizeHeaderIsDroppedWhole) {
  // A second "DF" inside the oversize header: rescanning finds it as another
  // (also oversize) candidate; without rescan the 10 header bytes go at once.
  Bytes stream = {'D', 'F', 'D', 'F', 0, 0, 0x30, 0, 0xff, 0xff};
  const Bytes good = OracleFrame(2, 0x0030, {});
  stream.insert(stream.end(), good.begin(), good.end());
  auto count_oversize = [](const std::vector<StreamEvent>& events) {
    size_t n = 0;
    for (const auto& e : events) {
      const auto* f = std::get_if<FramingError>(&e);
      n += f != nullptr && f->kind == FramingError::Kind::kOversize ? 1 : 0;
    }
    return n;
  };
  FrameDecoderOptions drop;
  drop.rescan_rejected = false;
  const auto dropped = DecodeChunked(stream, {3}, nullptr, drop);
  EXPECT_EQ(count_oversize(dropped), 1u);
  EXPECT_EQ(SkippedTotal(dropped), 10u);
  EXPECT_EQ(GoodFrames(dropped).size(), 1u);
  const auto rescanned = DecodeChunked(stream, {3});
  EXPECT_EQ(count_oversize(rescanned), 2u);
  EXPECT_EQ(GoodFrames(rescanned).size(), 1u);
}

TEST(DmcFrameDecoderTest, WithoutRescanFinishDropsThePendingCandidate) {
  const Bytes real = OracleFrame(77, 0x0031, {1, 0x10, 0, 0, 0});
  Bytes stream = {'D', 'F', 9, 9, 9, 9, 0x30, 0x00, 0x00, 0x04};  // Length 1024
  stream.insert(stream.end(), real.begin(), real.end());
  FrameDecoderOptions drop;
  drop.rescan_rejected = false;
  std::vector<StreamEvent> events;
  FrameDecoder dec(drop);
  auto collect = [&events](const FrameEvent& e) { events.push_back(ToStreamEvent(e)); };
  dec.Feed(stream, collect);
  dec.Finish(collect);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(std::get<FramingError>(events[0]).kind, FramingError::Kind::kTruncated);
  EXPECT_EQ(std::get<FramingError>(events[1]).bytes, stream.size());
  EXPECT_EQ(dec.pending_bytes(), 0u);
}

TEST(DmcFrameTest, PlausibleRequestHeaderIsAnUnflaggedTypeWithinTheReferenceMask) {
  EXPECT_TRUE(PlausibleRequestHeader(0x0031));
  EXPECT_TRUE(PlausibleRequestHeader(0x0077));  // unknown but could be sent
  EXPECT_TRUE(PlausibleRequestHeader(0x0204));
  EXPECT_FALSE(PlausibleRequestHeader(0x8031));  // a host's ACK
  EXPECT_FALSE(PlausibleRequestHeader(0x0400));
  EXPECT_FALSE(PlausibleRequestHeader(0x6820));  // " h": text after a "DF"
  int plausible = 0;
  for (uint32_t t = 0; t <= 0xffff; ++t) {
    plausible += PlausibleRequestHeader(static_cast<uint16_t>(t)) ? 1 : 0;
  }
  EXPECT_EQ(plausible, 0x10000 / 64);
}

TEST(DmcFrameDecoderTest, ResetForgetsPendingBytes) {
  FrameDecoder dec;
  std::vector<StreamEvent> events;
  auto collect = [&events](const FrameEvent& e) { events.push_back(ToStreamEvent(e)); };
  const Bytes f = OracleFrame(1, 0x0030, {});
  dec.Feed(ByteView(f).first(5), collect);
  EXPECT_EQ(dec.pending_bytes(), 5u);
  dec.Reset();
  EXPECT_EQ(dec.pending_bytes(), 0u);
  dec.Feed(f, collect);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(std::get<Frame>(events[0]).id, 1u);
}

}  // namespace
}  // namespace moco::dmc
