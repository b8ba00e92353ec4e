// Test support: a StackShot 3X broken on purpose at the wire. The real
// emulated controller with a filter on its output (each packet it writes,
// with the request it answers, handed to a Breakage) and, optionally, on its
// input (each host packet changed, or acknowledged without reaching the
// controller, or the raw bytes changed before it reads them), run through the
// whole runner; proving tests plant a fault this way and show the rule that
// names it failing (conformance/core/rule_proof_testing.h).
#ifndef MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_BROKEN_DEVICE_TESTING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_BROKEN_DEVICE_TESTING_H_

#include <gtest/gtest.h>

#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "devices/stackshot3x/stackshot3x.h"
#include "devices/stackshot3x/state_store.h"
#include "wire/stackshot.h"
#include "wire/stackshot_timing.h"

namespace moco::conformance::ss_testing {

using stackshot::Action;
using stackshot::Command;
using stackshot::Packet;

// Decides what becomes of one packet the controller wrote: `request` is the
// host packet it answers as the host sent it (nullptr: none), `out` the real
// link. Write with Emit().
using Breakage = std::function<void(const Packet* request, Packet reply, sim::Scheduler& s,
                                    devices::ByteSink& out)>;

// What becomes of one whole host packet before the controller reads it: the
// packet it reads instead, or nullopt for a controller that acknowledges it
// (RSP_OK, no data) without acting on it. A reply to a changed packet keeps
// the command id of the packet the host sent.
using RequestBreakage = std::function<std::optional<Packet>(const Packet& request)>;

// What becomes of the host's raw bytes before the controller reads them
// (framing faults); empty: read as sent. Runs before RequestBreakage.
using InputBreakage = std::function<wire::Bytes(wire::ByteView host_bytes, sim::Scheduler& s)>;

// Seals `p` as a device packet (negated-sum checksum) and writes it.
inline void Emit(devices::ByteSink& out, Packet p) {
  p.from_device = true;
  stackshot::Seal(p, stackshot::ChecksumAlgorithm::kNegatedSum);
  wire::Bytes bytes;
  stackshot::EncodePacket(p, bytes);
  out.Write(bytes);
}

inline void PassThrough(const Packet*, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
  Emit(out, std::move(reply));
}

// `reply` with status `status` and no data.
inline Packet WithStatus(Packet reply, Action status) {
  reply.action = static_cast<uint8_t>(status);
  reply.data.clear();
  return reply;
}

// Any status but RSP_OK.
inline bool Refused(const Packet& reply) {
  return reply.action != static_cast<uint8_t>(Action::kRspOk);
}

inline bool Is(const Packet* p, Command c) {
  return p != nullptr && p->command == stackshot::Id(c);
}

// The typed host request, or nullopt.
inline std::optional<stackshot::HostCommand> Typed(const Packet* p) {
  if (p == nullptr) return std::nullopt;
  auto t = stackshot::DecodeHostPacket(*p);
  if (!t) return std::nullopt;
  return std::move(t).value();
}

// The real StackShot 3X with a broken output stage (and, optionally, input stage).
class BrokenStackshot3x final : public devices::Device {
 public:
  BrokenStackshot3x(sim::Scheduler& s, devices::ByteSink& out, Breakage b,
                    devices::StateStore* store, RequestBreakage requests = {},
                    InputBreakage in = {})
      : s_(s),
        out_(out),
        breakage_(std::move(b)),
        requests_(std::move(requests)),
        in_(std::move(in)),
        replies_(*this),
        inner_(std::make_unique<devices::Stackshot3x>(s, replies_, devices::Stackshot3xProfile{},
                                                      store)) {
    RelayLineSwitchesOf(*inner_);
  }
  std::string_view Model() const override { return "stackshot3x-broken"; }
  devices::DeviceLine Line() const override { return inner_->Line(); }
  void PowerOn() override { inner_->PowerOn(); }
  void PowerOff() override { inner_->PowerOff(); }
  bool Powered() const override { return inner_->Powered(); }
  void OnHostLink(bool open) override { inner_->OnHostLink(open); }
  sim::Rig* rig() override { return inner_->rig(); }
  sim::GioPort* gio() override { return inner_->gio(); }
  bool HasButton(std::string_view button) const override { return inner_->HasButton(button); }
  void PressButton(std::string_view button) override { inner_->PressButton(button); }

  void OnHostBytes(wire::ByteView bytes) override {
    wire::Bytes changed;
    if (in_) {
      changed = in_(bytes, s_);
      bytes = changed;
    }
    // The spec's 2 ms inter-frame gap drops a partial packet (section 2).
    if (s_.Now() - last_byte_ns_ >= stackshot::kInterFrameGapNs) {
      host_decoder_.Flush();
    }
    last_byte_ns_ = s_.Now();
    scratch_.clear();
    host_decoder_.Feed(bytes, scratch_);
    if (!requests_) {
      for (const stackshot::DecodedPacket& d : scratch_) waiting_.push_back({d.packet, d.packet});
      inner_->OnHostBytes(bytes);
      return;
    }
    const std::vector<stackshot::DecodedPacket> packets = scratch_;
    for (const stackshot::DecodedPacket& d : packets) {
      std::optional<Packet> read = requests_(d.packet);
      if (!read) {
        Packet ack = d.packet;
        ack.from_device = true;
        ack.data.clear();
        ack.action = static_cast<uint8_t>(Action::kRspOk);
        waiting_.push_back({d.packet, d.packet});
        replies_.Write(Encoded(ack));
        continue;
      }
      read->from_device = false;
      waiting_.push_back({d.packet, *read});
      inner_->OnHostBytes(Encoded(*read));
    }
  }

 private:
  struct Waiting {
    Packet sent;  // as the host sent it
    Packet read;  // as the controller read it
  };

  static wire::Bytes Encoded(Packet p) {
    stackshot::Seal(p, stackshot::ChecksumAlgorithm::kNegatedSum);
    wire::Bytes bytes;
    stackshot::EncodePacket(p, bytes);
    return bytes;
  }

  // Cuts the controller's output into packets and hands each to the breakage
  // with the request it answers (the oldest waiting one with its command id).
  class Replies final : public devices::ByteSink {
   public:
    explicit Replies(BrokenStackshot3x& owner) : owner_(owner) {}
    void Write(wire::ByteView bytes) override {
      std::vector<stackshot::DecodedPacket> packets;
      decoder_.Feed(bytes, packets);
      for (stackshot::DecodedPacket& d : packets) owner_.OnReply(std::move(d.packet));
    }

   private:
    BrokenStackshot3x& owner_;
    stackshot::PacketDecoder decoder_{/*from_device=*/true};
  };

  void OnReply(Packet reply) {
    std::optional<Packet> request;
    for (size_t i = 0; i < waiting_.size(); ++i) {
      if (waiting_[i].read.command != reply.command) continue;
      request = waiting_[i].sent;
      waiting_.erase(waiting_.begin(), waiting_.begin() + static_cast<std::ptrdiff_t>(i) + 1);
      break;
    }
    if (request) reply.command = request->command;
    breakage_(request ? &*request : nullptr, std::move(reply), s_, out_);
  }

  sim::Scheduler& s_;
  devices::ByteSink& out_;
  Breakage breakage_;
  RequestBreakage requests_;
  InputBreakage in_;
  Replies replies_;
  stackshot::PacketDecoder host_decoder_{/*from_device=*/false};
  std::vector<stackshot::DecodedPacket> scratch_;
  std::deque<Waiting> waiting_;
  sim::TimeNs last_byte_ns_ = 0;
  std::unique_ptr<devices::Stackshot3x> inner_;
};

// Runs mococheck against the broken controller; its NVM outlives restarts.
inline RunReport RunBroken(Breakage b, RunOptions options = {}, RequestBreakage requests = {},
                           InputBreakage in = {}) {
  auto nvm = std::make_shared<devices::MemoryStateStore>();
  InProcessTarget target(
      "stackshot3x-broken", [b, requests, in, nvm](sim::Scheduler& s, devices::ByteSink& out) {
        return std::make_unique<BrokenStackshot3x>(s, out, b, nvm.get(), requests, in);
      });
  EXPECT_FALSE(target.Open().has_value());
  return RunStackshot(target, options);
}

using proof::ExpectCaught;

}  // namespace moco::conformance::ss_testing

#endif  // MOCO_CONFORMANCE_PROTOCOLS_STACKSHOT_STACKSHOT_BROKEN_DEVICE_TESTING_H_
