// Tests for link fault injection: deterministic for a seed, rates respected,
// each fault does what its definition in link_faults.h says.
#include "transport/link_faults.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <bit>
#include <cmath>

namespace moco::transport {
namespace {

using sim::kNsPerMs;

wire::Bytes Pattern(size_t n) {
  wire::Bytes b(n);
  for (size_t i = 0; i < n; ++i) b[i] = static_cast<uint8_t>(i * 37 + 11);
  return b;
}

wire::Bytes Flatten(const std::vector<TimedBytes>& chunks) {
  wire::Bytes out;
  for (const auto& c : chunks) out.insert(out.end(), c.bytes.begin(), c.bytes.end());
  return out;
}

FaultConfig Everything(uint64_t seed, double rate) {
  FaultConfig c;
  c.seed = seed;
  c.to_device = {rate, rate, rate, rate, 5 * kNsPerMs};
  c.to_host = c.to_device;
  return c;
}

TEST(LinkFaultsTest, OffByDefaultPassesBytesUnchanged) {
  FaultInjector f;
  EXPECT_FALSE(f.enabled());
  const wire::Bytes in = Pattern(100);
  const auto out = f.Apply(Direction::kToDevice, in, 42);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].at_ns, 42);
  EXPECT_EQ(out[0].bytes, in);
}

TEST(LinkFaultsTest, SameSeedSameOutput) {
  FaultInjector a(Everything(7, 0.05));
  FaultInjector b(Everything(7, 0.05));
  for (int i = 0; i < 50; ++i) {
    const wire::Bytes in = Pattern(97 + i);
    const auto oa = a.Apply(Direction::kToHost, in, i * kNsPerMs);
    const auto ob = b.Apply(Direction::kToHost, in, i * kNsPerMs);
    ASSERT_EQ(oa.size(), ob.size());
    for (size_t k = 0; k < oa.size(); ++k) {
      EXPECT_EQ(oa[k].at_ns, ob[k].at_ns);
      EXPECT_EQ(oa[k].bytes, ob[k].bytes);
    }
  }
}

TEST(LinkFaultsTest, DifferentSeedDifferentOutput) {
  FaultInjector a(Everything(7, 0.05));
  FaultInjector b(Everything(8, 0.05));
  const wire::Bytes in = Pattern(5000);
  EXPECT_NE(Flatten(a.Apply(Direction::kToHost, in, 0)),
            Flatten(b.Apply(Direction::kToHost, in, 0)));
}

TEST(LinkFaultsTest, DirectionsDrawFromIndependentStreams) {
  FaultInjector alone(Everything(3, 0.1));
  FaultInjector mixed(Everything(3, 0.1));
  const wire::Bytes in = Pattern(300);
  const wire::Bytes expect = Flatten(alone.Apply(Direction::kToDevice, in, 0));
  mixed.Apply(Direction::kToHost, Pattern(1000), 0);
  EXPECT_EQ(Flatten(mixed.Apply(Direction::kToDevice, in, 0)), expect);
}

// With a fixed seed the counts are fixed; check they lie within 5 standard
// deviations of the binomial mean n*p.
void ExpectNearRate(uint64_t count, uint64_t n, double p) {
  const double mean = static_cast<double>(n) * p;
  const double sd = std::sqrt(static_cast<double>(n) * p * (1 - p));
  EXPECT_NEAR(static_cast<double>(count), mean, 5 * sd) << "n=" << n << " p=" << p;
}

TEST(LinkFaultsTest, RatesAreRespected) {
  FaultConfig c;
  c.seed = 12345;
  c.to_device.drop_rate = 0.1;
  c.to_device.corrupt_rate = 0.02;
  c.to_device.duplicate_rate = 0.01;
  c.to_device.delay_rate = 0.001;
  c.to_device.delay_ns = 1;
  FaultInjector f(c);
  const size_t n = 200000;
  const wire::Bytes in = Pattern(n);
  const wire::Bytes out = Flatten(f.Apply(Direction::kToDevice, in, 0));
  const FaultCounts& k = f.counts(Direction::kToDevice);
  EXPECT_EQ(k.bytes_in, n);
  ExpectNearRate(k.dropped, n, 0.1);
  const uint64_t kept = n - k.dropped;
  ExpectNearRate(k.corrupted, kept, 0.02);
  ExpectNearRate(k.duplicated, kept, 0.01);
  ExpectNearRate(k.delayed, kept, 0.001);
  EXPECT_EQ(out.size(), kept + k.duplicated);
  // The other direction was not touched.
  EXPECT_EQ(f.counts(Direction::kToHost).bytes_in, 0u);
}

TEST(LinkFaultsTest, CorruptionFlipsExactlyOneBit) {
  FaultConfig c;
  c.to_host.corrupt_rate = 1.0;
  FaultInjector f(c);
  const wire::Bytes in = Pattern(1000);
  const wire::Bytes out = Flatten(f.Apply(Direction::kToHost, in, 0));
  ASSERT_EQ(out.size(), in.size());
  int bit_seen[8] = {};
  for (size_t i = 0; i < in.size(); ++i) {
    const unsigned diff = static_cast<unsigned>(in[i] ^ out[i]);
    ASSERT_EQ(std::popcount(diff), 1) << "byte " << i;
    ++bit_seen[std::countr_zero(diff)];
  }
  for (int b = 0; b < 8; ++b) EXPECT_GT(bit_seen[b], 50) << "bit " << b;
}

TEST(LinkFaultsTest, DuplicationRepeatsTheByteInPlace) {
  FaultConfig c;
  c.to_host.duplicate_rate = 1.0;
  FaultInjector f(c);
  const wire::Bytes in = {1, 2, 3};
  EXPECT_EQ(Flatten(f.Apply(Direction::kToHost, in, 0)), (wire::Bytes{1, 1, 2, 2, 3, 3}));
}

TEST(LinkFaultsTest, DropEverythingDeliversNothing) {
  FaultConfig c;
  c.to_device.drop_rate = 1.0;
  FaultInjector f(c);
  EXPECT_TRUE(f.Apply(Direction::kToDevice, Pattern(64), 0).empty());
  EXPECT_EQ(f.counts(Direction::kToDevice).dropped, 64u);
}

TEST(LinkFaultsTest, DelayStallsTheStreamInOrder) {
  FaultConfig c;
  c.to_device.delay_rate = 1.0;
  c.to_device.delay_ns = 10 * kNsPerMs;
  FaultInjector f(c);
  const wire::Bytes in = {'a', 'b', 'c'};
  const auto out = f.Apply(Direction::kToDevice, in, 1000);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].at_ns, 1000 + 10 * kNsPerMs);
  EXPECT_EQ(out[1].at_ns, 1000 + 20 * kNsPerMs);
  EXPECT_EQ(out[2].at_ns, 1000 + 30 * kNsPerMs);
  EXPECT_EQ(Flatten(out), in);
}

TEST(LinkFaultsTest, BytesAfterAStallWaitForIt) {
  FaultConfig c;
  c.seed = 99;
  c.to_host.delay_rate = 0.05;
  c.to_host.delay_ns = 3 * kNsPerMs;
  FaultInjector f(c);
  const wire::Bytes in = Pattern(2000);
  sim::TimeNs last = 0;
  wire::Bytes all;
  for (size_t i = 0; i < in.size(); i += 100) {
    const auto now = static_cast<sim::TimeNs>(i) * 1000;
    for (const auto& chunk : f.Apply(Direction::kToHost, wire::ByteView(in).subspan(i, 100), now)) {
      EXPECT_GE(chunk.at_ns, now);
      EXPECT_GE(chunk.at_ns, last);
      last = chunk.at_ns;
      all.insert(all.end(), chunk.bytes.begin(), chunk.bytes.end());
    }
  }
  EXPECT_EQ(all, in);  // delay never reorders or loses
  EXPECT_GT(f.counts(Direction::kToHost).delayed, 0u);
}

// Law: the bytes that come out do not depend on how the input was chunked.
RC_GTEST_PROP(LinkFaultsProp, OutputIndependentOfChunking, ()) {
  const auto seed = *rc::gen::arbitrary<uint64_t>();
  const auto in = *rc::gen::container<wire::Bytes>(rc::gen::arbitrary<uint8_t>());
  const auto cuts = *rc::gen::container<std::vector<size_t>>(rc::gen::inRange<size_t>(0, 64));
  FaultInjector whole(Everything(seed, 0.2));
  FaultInjector pieces(Everything(seed, 0.2));
  const wire::Bytes expect = Flatten(whole.Apply(Direction::kToDevice, in, 0));
  wire::Bytes got;
  size_t pos = 0;
  for (size_t cut : cuts) {
    const size_t n = std::min(cut, in.size() - pos);
    const auto out =
        Flatten(pieces.Apply(Direction::kToDevice, wire::ByteView(in).subspan(pos, n), 0));
    got.insert(got.end(), out.begin(), out.end());
    pos += n;
  }
  const auto rest = Flatten(pieces.Apply(Direction::kToDevice, wire::ByteView(in).subspan(pos), 0));
  got.insert(got.end(), rest.begin(), rest.end());
  RC_ASSERT(got == expect);
}

TEST(FaultConfigTest, ParsesAList) {
  const auto r = ParseFaultConfig("seed=42,drop=0.01,dir=to-host,corrupt=0.5,delay_ms=50");
  ASSERT_TRUE(std::holds_alternative<FaultConfig>(r)) << std::get<std::string>(r);
  const auto& c = std::get<FaultConfig>(r);
  EXPECT_EQ(c.seed, 42u);
  EXPECT_DOUBLE_EQ(c.to_device.drop_rate, 0.01);
  EXPECT_DOUBLE_EQ(c.to_host.drop_rate, 0.01);
  EXPECT_DOUBLE_EQ(c.to_device.corrupt_rate, 0.0);
  EXPECT_DOUBLE_EQ(c.to_host.corrupt_rate, 0.5);
  EXPECT_EQ(c.to_host.delay_ns, 50 * kNsPerMs);
  EXPECT_EQ(c.to_device.delay_ns, 20 * kNsPerMs);  // the default
}

TEST(FaultConfigTest, RejectsBadItemsWithAMessage) {
  auto err = [](std::string_view s) {
    const auto r = ParseFaultConfig(s);
    return std::holds_alternative<std::string>(r) ? std::get<std::string>(r) : std::string();
  };
  EXPECT_NE(err("drop=1.5").find("between 0 and 1"), std::string::npos);
  EXPECT_NE(err("drop=x").find("not a number"), std::string::npos);
  EXPECT_NE(err("jitter=0.1").find("unknown fault key"), std::string::npos);
  EXPECT_NE(err("dir=up").find("to-device"), std::string::npos);
  EXPECT_NE(err("drop").find("lacks '='"), std::string::npos);
  EXPECT_TRUE(err("").empty());
}

}  // namespace
}  // namespace moco::transport
