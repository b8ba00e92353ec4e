// A DMC v2 host for tests of the emulated DMC-16 in virtual time: encodes
// requests, feeds them to the device, decodes everything the device sends
// (recorded by devices/test_support.h) with the time it was sent.
#ifndef MOCO_DEVICES_DMC16_DMC16_TEST_SUPPORT_H_
#define MOCO_DEVICES_DMC16_DMC16_TEST_SUPPORT_H_

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "devices/dmc16/dmc16.h"
#include "devices/test_support.h"
#include "sim/scheduler.h"
#include "wire/dmc.h"

namespace moco::devices::testing {

// One frame the device sent, decoded.
struct Out {
  sim::TimeNs t_ns = 0;
  uint32_t id = 0;
  uint16_t type = 0;
  dmc::DeviceMessage msg;
};

class Host {
 public:
  explicit Host(Dmc16Profile profile = {}, bool power_on = true)
      : sink_(scheduler_), device_(scheduler_, sink_, std::move(profile)) {
    if (power_on) device_.PowerOn();
  }

  sim::Scheduler& scheduler() { return scheduler_; }
  Dmc16& device() { return device_; }
  // Everything the device sent, decoded (frames written since the last call
  // are decoded now, each with the time of its write).
  std::vector<Out>& out() {
    for (; decoded_ < sink_.chunks.size(); ++decoded_) {
      const RecordingSink::Chunk& c = sink_.chunks[decoded_];
      const wire::ByteView bytes(reinterpret_cast<const uint8_t*>(c.bytes.data()), c.bytes.size());
      decoder_.Feed(bytes, [&](const dmc::FrameEvent& e) {
        const auto* f = std::get_if<dmc::FrameRef>(&e);
        ASSERT_NE(f, nullptr) << "the device sent a frame that does not decode";
        dmc::Result<dmc::DeviceMessage> m = dmc::DecodeDeviceMessage(f->type, f->data);
        ASSERT_TRUE(m.ok()) << "device frame of type " << dmc::TypeName(f->type)
                            << " has a bad layout: " << m.error().detail;
        out_.push_back(Out{c.t_ns, f->id, f->type, m.value()});
      });
    }
    return out_;
  }
  sim::TimeNs now() const { return scheduler_.Now(); }

  // Sends a request with a fresh ID; returns the ID.
  uint32_t Send(const dmc::HostMessage& m) {
    const uint32_t id = next_id_++;
    device_.OnHostBytes(dmc::Encode(id, m));
    return id;
  }
  void SendRaw(const wire::Bytes& b) { device_.OnHostBytes(b); }
  RecordingSink& sink() { return sink_; }

  // The one reply to request `id` (fails the test unless exactly one).
  const Out& Reply(uint32_t id) {
    const Out* found = nullptr;
    int n = 0;
    for (const Out& o : out()) {
      if (o.id == id) {
        found = &o;
        ++n;
      }
    }
    EXPECT_EQ(n, 1) << "replies to request " << id;
    static const Out kNone{};
    return found != nullptr ? *found : kNone;
  }
  // The ACK code of the reply to `id`, or nullopt when it is not an ACK.
  std::optional<dmc::AckCode> AckOf(uint32_t id) {
    const Out& o = Reply(id);
    if (const auto* a = std::get_if<dmc::Ack>(&o.msg)) return static_cast<dmc::AckCode>(a->code);
    return std::nullopt;
  }
  // Sends and returns the ACK code (nullopt for a specific response).
  std::optional<dmc::AckCode> Request(const dmc::HostMessage& m) { return AckOf(Send(m)); }

  // Messages of type T the device sent, in order.
  template <typename T>
  std::vector<std::pair<sim::TimeNs, T>> All() {
    std::vector<std::pair<sim::TimeNs, T>> v;
    for (const Out& o : out()) {
      if (const auto* m = std::get_if<T>(&o.msg)) v.emplace_back(o.t_ns, *m);
    }
    return v;
  }
  void RunFor(sim::TimeNs ns) { scheduler_.RunUntil(scheduler_.Now() + ns); }
  void RunMs(int64_t ms) { RunFor(ms * sim::kNsPerMs); }
  void Settle() { scheduler_.RunUntilIdle(10'000'000); }
  int64_t Pos(int motor) { return device_.rig_ref().motor(motor).Position(); }

 private:
  sim::Scheduler scheduler_;
  RecordingSink sink_;
  Dmc16 device_;
  dmc::FrameDecoder decoder_;
  size_t decoded_ = 0;  // chunks of sink_ decoded into out_
  std::vector<Out> out_;
  // Far from the device's own sequence (from 1), so that a reply is told
  // apart from an unsolicited message by its ID.
  uint32_t next_id_ = 0x10000;
};

}  // namespace moco::devices::testing

#endif  // MOCO_DEVICES_DMC16_DMC16_TEST_SUPPORT_H_
