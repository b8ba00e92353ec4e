// Tests for UsbBridgePacer (usb_bridge_pacer.h): when each preset's packets
// reach the host, against the chips' documented behaviour (FACTS "USB serial
// bridges"; devices/usb_bridge.h).
#include "transport/usb_bridge_pacer.h"

#include <gtest/gtest.h>

#include <vector>

#include "transport/line_pacer.h"

namespace moco::transport {
namespace {

using devices::UsbBridge;
using sim::kNsPerMs;
using sim::TimeNs;

// Arrival times at the bridge of n bytes a UART at `bytes_per_second` sends
// from t0 on.
std::vector<TimeNs> Uart(size_t n, TimeNs t0, uint32_t bytes_per_second) {
  LinePacer uart(bytes_per_second);
  std::vector<TimeNs> out;
  for (size_t i = 0; i < n; ++i) out.push_back(uart.Take(t0));
  return out;
}

// Plays the bridge over `arrivals` as a link would: every packet, in order.
std::vector<UsbBridgePacer::Packet> Packets(UsbBridgePacer& pacer, std::vector<TimeNs> arrivals,
                                            TimeNs floor_ns = 0) {
  std::vector<UsbBridgePacer::Packet> out;
  size_t head = 0;
  while (head < arrivals.size()) {
    const auto p = pacer.Next(
        arrivals.size() - head, [&](size_t i) { return arrivals[head + i]; }, floor_ns);
    EXPECT_GT(p.bytes, 0u);
    if (p.bytes == 0) break;
    pacer.Sent(p);
    out.push_back(p);
    head += p.bytes;
  }
  return out;
}

TEST(UsbBridgePacer, FtdiSendsAShortReplyWholeAtTheLatencyTimersNextTick) {
  // A StackShot status reply: 10 bytes at 38400 8N1 (3840 bytes/s), from 3 ms.
  UsbBridgePacer ftdi(UsbBridge::Ftdi());
  const auto arrivals = Uart(10, 3 * kNsPerMs, 3840);
  ASSERT_LT(arrivals.back(), 16 * kNsPerMs);
  const auto packets = Packets(ftdi, arrivals);
  ASSERT_EQ(packets.size(), 1u);
  EXPECT_EQ(packets[0].bytes, 10u);
  EXPECT_EQ(packets[0].at_ns, 16 * kNsPerMs);
  EXPECT_FALSE(packets[0].full);
}

TEST(UsbBridgePacer, FtdiSendsAFullPacketOf62AtOnceAndRestartsItsTimer) {
  // 100 bytes from 0 at 115200 8N1 (11520 bytes/s): byte 62 arrives at
  // 5.38 ms, before the first tick.
  UsbBridgePacer ftdi(UsbBridge::Ftdi());
  const auto arrivals = Uart(100, 0, 11520);
  const auto packets = Packets(ftdi, arrivals);
  ASSERT_EQ(packets.size(), 2u);
  EXPECT_EQ(packets[0].bytes, 62u);
  EXPECT_TRUE(packets[0].full);
  EXPECT_EQ(packets[0].at_ns, arrivals[61]);
  // The rest leave one latency period after the full packet, not at 16 ms.
  EXPECT_EQ(packets[1].bytes, 38u);
  EXPECT_EQ(packets[1].at_ns, arrivals[61] + 16 * kNsPerMs);
  EXPECT_GE(packets[1].at_ns, arrivals.back());
}

TEST(UsbBridgePacer, FtdiAt38400NeverFillsAPacketBeforeItsDefaultTimer) {
  // 62 bytes take 16.15 ms at 3840 bytes/s: the 16 ms timer sends 61 first.
  UsbBridgePacer ftdi(UsbBridge::Ftdi());
  const auto packets = Packets(ftdi, Uart(62, 0, 3840));
  ASSERT_EQ(packets.size(), 2u);
  EXPECT_EQ(packets[0].bytes, 61u);
  EXPECT_EQ(packets[0].at_ns, 16 * kNsPerMs);
  EXPECT_EQ(packets[1].bytes, 1u);
  EXPECT_EQ(packets[1].at_ns, 32 * kNsPerMs);
}

TEST(UsbBridgePacer, FtdiLatencyFromTheProfileSetsTheTick) {
  // 6 bytes from 5 ms at 3840 bytes/s arrive at 5.26, 5.52, 5.78, 6.04,
  // 6.30 and 6.56 ms; a 2 ms timer splits them at its 6 ms tick.
  UsbBridgePacer ftdi(UsbBridge::Ftdi(2));
  const auto packets = Packets(ftdi, Uart(6, 5 * kNsPerMs, 3840));
  ASSERT_EQ(packets.size(), 2u);
  EXPECT_EQ(packets[0].bytes, 3u);
  EXPECT_EQ(packets[0].at_ns, 6 * kNsPerMs);
  EXPECT_EQ(packets[1].bytes, 3u);
  EXPECT_EQ(packets[1].at_ns, 8 * kNsPerMs);
}

TEST(UsbBridgePacer, CdcSendsFullPacketsAtOnceAndTheRestInTheNextFrame) {
  // A CDC device writes 200 bytes at 2.5 ms: no UART, 64-byte packets.
  UsbBridgePacer cdc(UsbBridge::Cdc());
  const std::vector<TimeNs> arrivals(200, 2'500'000);
  const auto packets = Packets(cdc, arrivals);
  ASSERT_EQ(packets.size(), 4u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(packets[i].bytes, 64u);
    EXPECT_EQ(packets[i].at_ns, 2'500'000);
  }
  EXPECT_EQ(packets[3].bytes, 8u);
  EXPECT_EQ(packets[3].at_ns, 3 * kNsPerMs);
}

TEST(UsbBridgePacer, Arduino16u2FlushesEvery4096UsOrAbove96Bytes) {
  // DFMoco's `mp 1 1000\r\n` at 57600 8N1 (5760 bytes/s) from 10 ms: 11 bytes
  // done by 11.91 ms; Timer0 overflows at multiples of 4.096 ms: 12.288 ms.
  UsbBridgePacer u2(UsbBridge::Arduino16u2());
  auto packets = Packets(u2, Uart(11, 10 * kNsPerMs, 5760));
  ASSERT_EQ(packets.size(), 1u);
  EXPECT_EQ(packets[0].bytes, 11u);
  EXPECT_EQ(packets[0].at_ns, 12'288'000);
  // Bytes arriving faster than the timer empties the ring: the 97th byte
  // sends the ring at once.
  UsbBridgePacer fast(UsbBridge::Arduino16u2());
  const std::vector<TimeNs> burst(120, 100'000);
  packets = Packets(fast, burst);
  ASSERT_EQ(packets.size(), 2u);
  EXPECT_EQ(packets[0].bytes, 97u);
  EXPECT_EQ(packets[0].at_ns, 100'000);
  EXPECT_EQ(packets[1].bytes, 23u);
  EXPECT_EQ(packets[1].at_ns, 4'096'000);
}

TEST(UsbBridgePacer, NothingLeavesBeforeTheFloorOrBeforeItsLastByteArrived) {
  // Bytes held while the host was away leave at the first tick after it came.
  UsbBridgePacer ftdi(UsbBridge::Ftdi());
  const auto packets = Packets(ftdi, Uart(5, 0, 3840), 40 * kNsPerMs);
  ASSERT_EQ(packets.size(), 1u);
  EXPECT_EQ(packets[0].at_ns, 48 * kNsPerMs);
  // Law: for every preset and arrival pattern, a packet never leaves before
  // its own last byte arrived, and packets leave in order.
  for (const UsbBridge& b :
       {UsbBridge::Ftdi(), UsbBridge::Ftdi(1), UsbBridge::Cdc(), UsbBridge::Arduino16u2()}) {
    for (uint32_t rate : {960u, 3840u, 5760u, 11520u, 1'000'000u}) {
      UsbBridgePacer pacer(b);
      std::vector<TimeNs> arrivals = Uart(300, 777, rate);
      const auto more = Uart(40, arrivals.back() + 50 * kNsPerMs, rate);
      arrivals.insert(arrivals.end(), more.begin(), more.end());
      size_t head = 0;
      TimeNs last = 0;
      for (const auto& p : Packets(pacer, arrivals)) {
        EXPECT_GE(p.at_ns, arrivals[head + p.bytes - 1]) << b.Name() << " at " << rate;
        EXPECT_GE(p.at_ns, last);
        if (b.flush_at_bytes != 0) {
          EXPECT_LE(p.bytes, b.flush_at_bytes);
        }
        last = p.at_ns;
        head += p.bytes;
      }
      EXPECT_EQ(head, arrivals.size());
    }
  }
}

TEST(UsbBridgePacer, NoBridgeIsInactive) {
  EXPECT_FALSE(UsbBridgePacer().active());
  EXPECT_FALSE(UsbBridgePacer(UsbBridge::None()).active());
  EXPECT_TRUE(UsbBridgePacer(UsbBridge::Cdc()).active());
}

}  // namespace
}  // namespace moco::transport
