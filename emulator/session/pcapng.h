// A session as a pcapng capture, for Wireshark and tshark (docs/wireshark.md):
// one Section Header Block, one Interface Description Block per direction
// (interface 0: host -> device, interface 1: device -> host), and one
// Enhanced Packet Block per traffic chunk with its time in nanoseconds and
// the direction in its flags. The link type is LINKTYPE_USER0 (147): the
// packets hold the link's bytes exactly as they crossed it, no pseudo-header;
// tools/wireshark/mocosim.lua registers on it. The interfaces' descriptions
// name the protocol ("mocosim dmc host->device") so the dissector knows it.
// A "line_switch" event (docs/sessions.md) adds a pair of interfaces named
// with the new protocol, and the packets after it are on them: interface
// 2k is host -> device, 2k + 1 device -> host, for the k-th protocol the
// line spoke.
#ifndef MOCO_SESSION_PCAPNG_H_
#define MOCO_SESSION_PCAPNG_H_

#include <cstddef>
#include <cstdint>
#include <string>

#include "session/session.h"

namespace moco::session {

// LINKTYPE_USER0 of the tcpdump.org link-type registry.
inline constexpr uint16_t kPcapngLinkTypeUser0 = 147;
// A chunk longer than this is written as several packets with the same
// time: Wireshark refuses packets above 256 KiB, and no message of the three
// protocols is near this size.
inline constexpr size_t kPcapngMaxPacketBytes = 65535;

// The interface a direction's packets are on (before any line switch; after
// the k-th, 2k more).
inline constexpr uint32_t kPcapngHostToDevice = 0;
inline constexpr uint32_t kPcapngDeviceToHost = 1;

struct PcapngStats {
  size_t packets = 0;          // Enhanced Packet Blocks written
  size_t bytes = 0;            // traffic bytes in them
  size_t events_left_out = 0;  // event lines (control, faults): not traffic, not exported
  size_t line_switches = 0;    // "line_switch" events: a pair of interfaces each
};

// The whole capture file for `session`. Chunks with no bytes are left out;
// a negative time counts as 0. Never throws (apart from std::bad_alloc).
std::string SessionToPcapng(const Session& session, PcapngStats* stats = nullptr);

}  // namespace moco::session

#endif  // MOCO_SESSION_PCAPNG_H_
