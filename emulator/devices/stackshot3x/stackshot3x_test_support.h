// Test bench for the StackShot 3X device in virtual time: a recording sink, a
// memory NVM store and helpers that speak the binary protocol.
#ifndef MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_TEST_SUPPORT_H_
#define MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_TEST_SUPPORT_H_

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "devices/stackshot3x/stackshot3x.h"
#include "devices/test_support.h"
#include "wire/stackshot.h"

namespace moco::devices::testing {

struct SsBench {
  explicit SsBench(Stackshot3xProfile profile = {}, StateStore* external = nullptr)
      : sink(sched),
        store(external != nullptr ? external : &memory),
        dev(std::make_unique<Stackshot3x>(sched, sink, std::move(profile), store)) {
    dev->PowerOn();
  }
  void Feed(const wire::Bytes& b) { dev->OnHostBytes(b); }
  void Send(const stackshot::HostCommand& c) {
    wire::Bytes b;
    stackshot::EncodeHostCommand(c, b);
    Feed(b);
  }
  void RunFor(sim::TimeNs d) { sched.RunUntil(sched.Now() + d); }
  // Every reply packet written since the last call.
  std::vector<stackshot::Packet> Replies() {
    stackshot::PacketDecoder d(/*from_device=*/true);
    std::vector<stackshot::DecodedPacket> out;
    d.Feed(sink.Take(), out);
    std::vector<stackshot::Packet> packets;
    for (auto& p : out) packets.push_back(std::move(p.packet));
    return packets;
  }
  // Sends `c`, lets `window` pass and returns the one reply (an empty packet
  // with command 0 when there was not exactly one).
  stackshot::Packet Ask(const stackshot::HostCommand& c, sim::TimeNs window = sim::kNsPerMs) {
    Send(c);
    RunFor(window);
    auto r = Replies();
    return r.size() == 1 ? r[0] : stackshot::Packet{};
  }
  stackshot::Action Status(const stackshot::HostCommand& c) {
    return static_cast<stackshot::Action>(Ask(c).action);
  }
  // The typed reply to a READ.
  stackshot::DeviceReply AskRead(const stackshot::HostCommand& c) {
    const stackshot::Packet p = Ask(c);
    auto r = stackshot::DecodeDevicePacket(p, stackshot::ReplyContext{stackshot::Action::kRead});
    return r ? *r : stackshot::DeviceReply{};
  }

  sim::Scheduler sched;
  RecordingSink sink;
  MemoryStateStore memory;
  StateStore* store;
  std::unique_ptr<Stackshot3x> dev;
};

inline stackshot::HostCommand Read(stackshot::Command c, uint8_t axis = 0,
                                   stackshot::Payload payload = stackshot::Empty{},
                                   bool sub_item = false) {
  return stackshot::HostCommand{stackshot::Id(c),  stackshot::Action::kRead, axis, sub_item, false,
                                std::move(payload)};
}
inline stackshot::HostCommand Write(stackshot::Command c, uint8_t axis = 0,
                                    stackshot::Payload payload = stackshot::Empty{},
                                    bool sub_item = false) {
  return stackshot::HostCommand{stackshot::Id(c),  stackshot::Action::kWrite, axis, sub_item, false,
                                std::move(payload)};
}

}  // namespace moco::devices::testing

#endif  // MOCO_DEVICES_STACKSHOT3X_STACKSHOT3X_TEST_SUPPORT_H_
