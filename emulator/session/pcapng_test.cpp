// Tests for the pcapng export (session/pcapng.h): the file is read back
// block by block as the pcapng specification lays it out (draft-ietf-opsawg-
// pcapng sections 3 and 4), so a writer that breaks the layout fails here
// before Wireshark ever sees it.
#include "session/pcapng.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace moco::session {
namespace {

uint32_t U32At(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<uint8_t>(s.at(at + i));
  return v;
}
uint16_t U16At(const std::string& s, size_t at) {
  return static_cast<uint16_t>(static_cast<uint8_t>(s.at(at)) |
                               (static_cast<uint8_t>(s.at(at + 1)) << 8));
}

struct Option {
  uint16_t code = 0;
  std::string value;
};
struct Block {
  uint32_t type = 0;
  std::string body;  // between the leading and trailing total lengths
};
struct Packet {
  uint32_t interface = 0;
  uint64_t t = 0;
  std::string bytes;
  uint32_t flags = 0;
};
struct Capture {
  std::vector<Block> blocks;
  std::vector<Packet> packets;
  std::vector<std::vector<Option>> interfaces;  // options of each IDB
  std::vector<uint16_t> link_types;
  std::vector<Option> section_options;
};

std::vector<Option> Options(const std::string& body, size_t at) {
  std::vector<Option> out;
  while (at + 4 <= body.size()) {
    const uint16_t code = U16At(body, at);
    const uint16_t len = U16At(body, at + 2);
    if (code == 0) break;
    out.push_back({code, body.substr(at + 4, len)});
    at += 4 + (len + 3u) / 4u * 4u;
  }
  return out;
}

// Reads every block, checking the framing each block must have.
Capture Read(const std::string& file) {
  Capture c;
  size_t at = 0;
  while (at < file.size()) {
    const uint32_t type = U32At(file, at);
    const uint32_t total = U32At(file, at + 4);
    EXPECT_EQ(total % 4, 0u) << "block at " << at;
    EXPECT_GE(total, 12u);
    EXPECT_LE(at + total, file.size());
    if (total < 12 || at + total > file.size()) return c;
    EXPECT_EQ(U32At(file, at + total - 4), total) << "trailing length of block at " << at;
    Block b{type, file.substr(at + 8, total - 12)};
    if (type == 0x0A0D0D0A) {
      EXPECT_EQ(U32At(b.body, 0), 0x1A2B3C4Du);
      EXPECT_EQ(U16At(b.body, 4), 1);
      EXPECT_EQ(U16At(b.body, 6), 0);
      c.section_options = Options(b.body, 16);
    } else if (type == 1) {
      c.link_types.push_back(U16At(b.body, 0));
      c.interfaces.push_back(Options(b.body, 8));
    } else if (type == 6) {
      Packet p;
      p.interface = U32At(b.body, 0);
      p.t = (uint64_t{U32At(b.body, 4)} << 32) | U32At(b.body, 8);
      const uint32_t captured = U32At(b.body, 12);
      EXPECT_EQ(U32At(b.body, 16), captured);
      p.bytes = b.body.substr(20, captured);
      for (const Option& o : Options(b.body, 20 + (captured + 3u) / 4u * 4u)) {
        if (o.code == 2) p.flags = U32At(o.value, 0);
      }
      c.packets.push_back(p);
    }
    c.blocks.push_back(std::move(b));
    at += total;
  }
  return c;
}

std::string OptionText(const std::vector<Option>& options, uint16_t code) {
  for (const Option& o : options) {
    if (o.code == code) return o.value;
  }
  return {};
}

SessionEntry Traffic(int64_t t, Origin from, std::vector<uint8_t> bytes) {
  SessionEntry e;
  e.t_ns = t;
  e.from = from;
  e.bytes = std::move(bytes);
  return e;
}

TEST(PcapngTest, EachChunkIsOnePacketWithItsTimeDirectionAndExactBytes) {
  Session s;
  s.header.protocol = Protocol::kDmc;
  s.header.note = "a note";
  s.entries.push_back(Traffic(500000000, Origin::kHost, {0x44, 0x46, 0x01}));
  s.entries.push_back(Traffic(501000123, Origin::kDevice, {0x44, 0x46, 0x02, 0x03, 0x04}));
  s.entries.push_back(SessionEntry::Event({{"t_ns", 600000000}, {"event", "estop"}}));
  s.entries.push_back(Traffic(int64_t{5} << 32, Origin::kHost, {0x00}));
  PcapngStats stats;
  const Capture c = Read(SessionToPcapng(s, &stats));

  ASSERT_EQ(c.blocks.size(), 6u);  // SHB, 2 IDB, 3 EPB
  EXPECT_EQ(c.blocks[0].type, 0x0A0D0D0Au);
  EXPECT_EQ(OptionText(c.section_options, 1), "a note");
  ASSERT_EQ(c.link_types, (std::vector<uint16_t>{147, 147}));
  EXPECT_EQ(OptionText(c.interfaces[0], 2), "host->device");
  EXPECT_EQ(OptionText(c.interfaces[0], 3), "mocosim dmc host->device");
  EXPECT_EQ(OptionText(c.interfaces[1], 3), "mocosim dmc device->host");
  EXPECT_EQ(OptionText(c.interfaces[0], 9), std::string(1, '\x09'));  // nanoseconds

  ASSERT_EQ(c.packets.size(), 3u);
  EXPECT_EQ(c.packets[0].interface, kPcapngHostToDevice);
  EXPECT_EQ(c.packets[0].t, 500000000u);
  EXPECT_EQ(c.packets[0].bytes, std::string("\x44\x46\x01"));
  EXPECT_EQ(c.packets[0].flags, 2u);  // outbound from the host
  EXPECT_EQ(c.packets[1].interface, kPcapngDeviceToHost);
  EXPECT_EQ(c.packets[1].t, 501000123u);
  EXPECT_EQ(c.packets[1].bytes, std::string("\x44\x46\x02\x03\x04"));
  EXPECT_EQ(c.packets[1].flags, 1u);             // inbound
  EXPECT_EQ(c.packets[2].t, uint64_t{5} << 32);  // both halves of the timestamp
  EXPECT_EQ(c.packets[2].bytes, std::string(1, '\0'));
  EXPECT_EQ(stats.packets, 3u);
  EXPECT_EQ(stats.bytes, 9u);
  EXPECT_EQ(stats.events_left_out, 1u);
}

// A recorded line switch: a pair of interfaces named with the new protocol,
// and the packets after it on them; a switch to the protocol already spoken
// changes nothing.
TEST(PcapngTest, ALineSwitchStartsAPairOfInterfacesNamedWithTheNewProtocol) {
  Session s;
  s.header.protocol = Protocol::kStackshot;
  s.entries.push_back(Traffic(1, Origin::kHost, {0x55}));
  s.entries.push_back(LineSwitchEvent(2, Protocol::kStackshotDfmoco, {.baud = 57600}));
  s.entries.push_back(LineSwitchEvent(2, Protocol::kStackshotDfmoco, {.baud = 57600}));
  s.entries.push_back(Traffic(3, Origin::kHost, {'h'}));
  s.entries.push_back(Traffic(4, Origin::kDevice, {'h'}));
  PcapngStats stats;
  const Capture c = Read(SessionToPcapng(s, &stats));
  ASSERT_EQ(c.interfaces.size(), 4u);
  EXPECT_EQ(OptionText(c.interfaces[2], 3), "mocosim stackshot-dfmoco host->device");
  EXPECT_EQ(OptionText(c.interfaces[3], 3), "mocosim stackshot-dfmoco device->host");
  ASSERT_EQ(c.packets.size(), 3u);
  EXPECT_EQ(c.packets[0].interface, kPcapngHostToDevice);
  EXPECT_EQ(c.packets[1].interface, 2 + kPcapngHostToDevice);
  EXPECT_EQ(c.packets[2].interface, 2 + kPcapngDeviceToHost);
  EXPECT_EQ(stats.line_switches, 1u);
  EXPECT_EQ(stats.events_left_out, 0u);
}

TEST(PcapngTest, AChunkLongerThanAPacketIsSplitInOrderAtTheSameTime) {
  Session s;
  s.header.protocol = Protocol::kStackshot;
  std::vector<uint8_t> big(kPcapngMaxPacketBytes * 2 + 10);
  for (size_t i = 0; i < big.size(); ++i) big[i] = static_cast<uint8_t>(i * 7);
  s.entries.push_back(Traffic(42, Origin::kDevice, big));
  const Capture c = Read(SessionToPcapng(s));
  ASSERT_EQ(c.packets.size(), 3u);
  std::string joined;
  for (const Packet& p : c.packets) {
    EXPECT_EQ(p.t, 42u);
    EXPECT_LE(p.bytes.size(), kPcapngMaxPacketBytes);
    joined += p.bytes;
  }
  EXPECT_EQ(joined, std::string(big.begin(), big.end()));
  EXPECT_EQ(OptionText(c.interfaces[1], 3), "mocosim stackshot device->host");
}

TEST(PcapngTest, EmptyChunksAndNegativeTimesDoNotBreakTheFile) {
  Session s;
  s.entries.push_back(Traffic(-5, Origin::kHost, {0x01}));
  s.entries.push_back(Traffic(7, Origin::kHost, {}));
  PcapngStats stats;
  const Capture c = Read(SessionToPcapng(s, &stats));
  ASSERT_EQ(c.packets.size(), 1u);
  EXPECT_EQ(c.packets[0].t, 0u);
  EXPECT_EQ(stats.packets, 1u);
  // A session with no entries is still a valid capture: a section, two interfaces.
  EXPECT_EQ(Read(SessionToPcapng(Session{})).blocks.size(), 3u);
}

// Whatever the chunks, the packets carry the session's bytes per direction
// in order, and every block is framed as the specification requires.
RC_GTEST_PROP(PcapngTest, PacketsReproduceEachDirectionsStream,
              (const std::vector<std::pair<bool, std::vector<uint8_t>>>& chunks)) {
  Session s;
  s.header.note = *rc::gen::arbitrary<std::string>();
  std::string host, device;
  int64_t t = 0;
  for (const auto& [from_host, bytes] : chunks) {
    s.entries.push_back(Traffic(t += 13, from_host ? Origin::kHost : Origin::kDevice, bytes));
    (from_host ? host : device).append(bytes.begin(), bytes.end());
  }
  std::string got_host, got_device;
  for (const Packet& p : Read(SessionToPcapng(s)).packets) {
    (p.interface == kPcapngHostToDevice ? got_host : got_device) += p.bytes;
    RC_ASSERT((p.interface == kPcapngHostToDevice) == (p.flags == 2u));
  }
  RC_ASSERT(got_host == host);
  RC_ASSERT(got_device == device);
}

}  // namespace
}  // namespace moco::session
