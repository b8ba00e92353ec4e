// A Dragonframe-style DMC v2 host over a Target (dmc-v2-protocol.txt "Message
// Format", "MSG_FLAG_ACK"; ERRATA 1.1-1.4, 1.9): sends requests with host IDs,
// frames every device byte, matches answers to requests and checks each
// device frame against the stream rules (framing, checksum, one answer per
// request with its ID and a legal Type, ACK codes, response layouts, deadlines).
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_HOST_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_HOST_H_

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "conformance/core/host_link.h"
#include "conformance/core/verdicts.h"
#include "conformance/targets/target.h"
#include "wire/dmc.h"

namespace moco::conformance {

// One frame the device sent (checksum good).
struct DmcRecord {
  TimeNs t_ns = 0;
  uint32_t id = 0;
  uint16_t type = 0;
  wire::Bytes raw;
  std::optional<dmc::DeviceMessage> msg;  // nullopt when the data fits no layout
  int request = -1;                       // index of the request it answers; -1: unsolicited
};

struct DmcRequest {
  uint32_t id = 0;
  uint16_t type = 0;
  TimeNs sent_ns = 0;
  wire::Bytes raw;
  bool bad_checksum = false;
  bool well_formed = false;  // a good checksum and a layout that fits its type
  int answer = -1;           // index into records()
  int answers = 0;
  // The device sent a frame with this request's ID whose checksum failed:
  // its answer came, unreadable.
  bool garbled_answer = false;
};

class DmcHost : public HostBase {
 public:
  // The first host ID; device-side IDs of unsolicited messages count from 1,
  // so the two ranges do not meet in a run.
  static constexpr uint32_t kFirstHostId = 0x00010001;

  // `target` and `verdicts` must outlive the host. The target is open.
  DmcHost(Target& target, Verdicts& verdicts, HostOptions options);

  // Sends `m` with the next host ID; returns the ID.
  uint32_t Send(const dmc::HostMessage& m);
  // Sends a frame of any type and data with the next host ID. With
  // `corrupt_checksum` the last check byte is altered (header intact).
  uint32_t SendFrame(uint16_t type, wire::ByteView data, bool corrupt_checksum = false);
  // Sends bytes that are not a request (noise, a partial header) as they are.
  void SendNoise(wire::ByteView bytes);
  // Sends a request one byte at a time, reading in between.
  uint32_t SendBytewise(const dmc::HostMessage& m);

  // Waits for the answer to request `id` (DMC-ACK-001 fails after the answer
  // timeout, or after `timeout_ns` when given); returns it or nullptr.
  const DmcRecord* Await(uint32_t id, std::optional<TimeNs> timeout_ns = std::nullopt);
  const DmcRecord* Call(const dmc::HostMessage& m) { return Await(Send(m)); }

  // Reads until a record with index >= `from` satisfies `pred` or `timeout_ns`
  // passes; returns its index or -1.
  int WaitFor(size_t from, TimeNs timeout_ns, const std::function<bool(const DmcRecord&)>& pred);
  // Ends the case: listens for the quiet time, gives up on any partial device
  // frame, and settles the stream rules. Call once.
  void Close();

  // A deque: pointers to records stay valid while more arrive.
  const std::deque<DmcRecord>& records() const { return records_; }
  const std::vector<DmcRequest>& requests() const { return requests_; }

  // The last HI the device sent (answer or unsolicited), if any.
  const std::optional<dmc::HiResponse>& hi() const { return hi_; }
  // Whether the host ACKs the device's unsolicited messages (Dragonframe does).
  void set_ack_unsolicited(bool on) { ack_unsolicited_ = on; }

 private:
  uint32_t SendRaw(uint32_t id, uint16_t type, wire::Bytes bytes, bool bad_checksum);
  void OnBytes(wire::ByteView bytes);
  void OnFrame(const dmc::FrameRef& f);
  void CheckAnswer(DmcRequest& req, const DmcRecord& rec);
  void CheckGioIn(const DmcRecord& rec);
  void CheckUnsolicited(const DmcRecord& rec);
  void CheckHi(const DmcRecord& rec, const dmc::HiResponse& hi);
  void CheckSpecific(const DmcRequest& req, const DmcRecord& rec);
  Evidence Ev(const DmcRecord& rec, std::string expected, std::string observed) const;

  dmc::FrameDecoder decoder_;
  wire::Bytes history_;  // the device stream (for the bytes of bad frames)
  std::deque<DmcRecord> records_;
  std::vector<DmcRequest> requests_;
  std::optional<dmc::HiResponse> hi_;
  std::optional<dmc::HiResponse> previous_hi_;  // the one before hi_ (DMC-HI-012)
  std::set<uint32_t> acked_ids_;                // device IDs the host ACKed
  uint32_t next_id_ = kFirstHostId;
  bool ack_unsolicited_ = true;
  bool closed_ = false;
  size_t skipped_bytes_ = 0;
};

// The message of `rec` as T, or nullptr.
template <typename T>
const T* As(const DmcRecord* rec) {
  if (rec == nullptr || !rec->msg) return nullptr;
  return std::get_if<T>(&*rec->msg);
}
// The response code when `rec` is an ACK.
std::optional<uint32_t> AckCodeOf(const DmcRecord* rec);
// "ACK ERR_RANGE", "MOTOR_MOVE moving=1", "no answer".
std::string Show(const DmcRecord* rec);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_HOST_H_
