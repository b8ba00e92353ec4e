// A StackShot 3X host over a Target (stackshot-protocol.txt section 2;
// ERRATA stackshot 1-4, 6; FACTS "StackShot"): sends typed requests, cuts the
// device's bytes into packets with the codec, pairs each reply with the
// oldest request still waiting (the protocol has no ids: one request, one
// reply, in order) and checks every device packet against the stream rules
// (SS-PKT, SS-CSUM, SS-ANS, SS-CODE, SS-LAYOUT, SS-ERR-001..003, SS-PING-001,
// SS-STATUS-001, SS-DL).
#ifndef MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_HOST_H_
#define MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_HOST_H_

#include <cstdint>
#include <deque>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "conformance/core/host_link.h"
#include "conformance/core/verdicts.h"
#include "conformance/targets/target.h"
#include "wire/stackshot.h"

namespace moco::conformance {

// One packet the host sent.
struct SsRequest {
  TimeNs sent_ns = 0;
  stackshot::Packet packet;
  wire::Bytes raw;
  // The typed request when it decodes; nullopt for a packet the device must
  // refuse (an action the command does not allow, a wrong length).
  std::optional<stackshot::HostCommand> cmd;
  std::optional<stackshot::Action> refusal;  // what the codec says the device answers then
  bool given_up = false;                     // unanswered after the answer timeout
  int answer = -1;                           // index into records()
};

// One packet the device sent.
struct SsRecord {
  TimeNs t_ns = 0;
  stackshot::Packet packet;
  wire::Bytes raw;
  std::optional<stackshot::DeviceReply> reply;  // nullopt when the data fits no layout
  int request = -1;                             // the request it answers; -1: none
};

class SsHost : public HostBase {
 public:
  // `target` and `verdicts` must outlive the host. The target is open.
  // `checksum`: what the host puts in its checksum bytes.
  SsHost(Target& target, Verdicts& verdicts, HostOptions options,
         stackshot::ChecksumAlgorithm checksum = stackshot::kDefaultChecksum);

  // Sends a typed request; returns its index in requests().
  int Send(const stackshot::HostCommand& c);
  // Sends a packet as given (any action, length and checksum byte).
  int SendPacket(const stackshot::Packet& p);
  // Sends a request one byte at a time, reading in between.
  int SendBytewise(const stackshot::HostCommand& c);
  // Sends bytes that are not a whole request (noise, a partial packet).
  void SendNoise(wire::ByteView bytes);

  // Waits for the reply to request `index` (SS-ANS-001 fails after the
  // answer timeout); returns it or nullptr.
  const SsRecord* Await(int index);
  const SsRecord* Call(const stackshot::HostCommand& c) { return Await(Send(c)); }

  // Ends the case: listens for the quiet time, judges a partial device packet
  // (SS-PKT-002) and the checksum family. Call once.
  void Close();

  // A deque: pointers to records stay valid while more arrive.
  const std::deque<SsRecord>& records() const { return records_; }
  const std::vector<SsRequest>& requests() const { return requests_; }
  stackshot::ChecksumAlgorithm checksum() const { return checksum_; }
  void set_checksum(stackshot::ChecksumAlgorithm c) { checksum_ = c; }

 private:
  int Record(stackshot::Packet p, wire::Bytes raw);
  void OnBytes(wire::ByteView bytes);
  void OnPacket(const stackshot::DecodedPacket& d);
  void CheckReply(const SsRequest& req, const SsRecord& rec);
  void CheckChecksum(const SsRecord& rec);
  Evidence Ev(const SsRecord& rec, std::string expected, std::string observed) const;

  stackshot::ChecksumAlgorithm checksum_;
  stackshot::PacketDecoder decoder_;
  std::vector<stackshot::DecodedPacket> scratch_;
  std::deque<SsRecord> records_;
  std::vector<SsRequest> requests_;
  std::deque<int> waiting_;  // requests without a reply, oldest first
  // SS-CSUM-002: the algorithms every device packet so far agrees with.
  std::set<stackshot::ChecksumAlgorithm> consistent_;
  uint64_t reported_skipped_ = 0;  // skipped bytes judged with the packet after them
  bool closed_ = false;
};

// Typed requests. `axis` goes into bits 4-5 of the action byte.
stackshot::HostCommand SsRead(stackshot::Command c, stackshot::Payload payload = stackshot::Empty{},
                              uint8_t axis = 0, bool sub_item = false);
stackshot::HostCommand SsWrite(stackshot::Command c,
                               stackshot::Payload payload = stackshot::Empty{}, uint8_t axis = 0,
                               bool sub_item = false);

// The reply's status, or nullopt without a reply.
std::optional<stackshot::Action> StatusOf(const SsRecord* rec);
// The payload of a typed reply as T, or nullptr.
template <typename T>
const T* PayloadOf(const SsRecord* rec) {
  if (rec == nullptr || !rec->reply) return nullptr;
  return std::get_if<T>(&rec->reply->payload);
}
// "CC_RAIL_STATUS ok axis=X status=moving", "no answer".
std::string Show(const SsRecord* rec);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_HOST_H_
