// Test support shared by the device families' tests: a ByteSink that records
// what a device writes, each write with the scheduler's time (devices write
// only to a ByteSink and keep time only through the Scheduler, device.h).
#ifndef MOCO_DEVICES_TEST_SUPPORT_H_
#define MOCO_DEVICES_TEST_SUPPORT_H_

#include <string>
#include <vector>

#include "devices/device.h"
#include "sim/scheduler.h"
#include "wire/bytes.h"

namespace moco::devices::testing {

class RecordingSink final : public ByteSink {
 public:
  // One Write: its time and its bytes (as a string, so text devices compare
  // with text).
  struct Chunk {
    sim::TimeNs t_ns = 0;
    std::string bytes;
    bool operator==(const Chunk&) const = default;
  };

  // `scheduler` must outlive the sink.
  explicit RecordingSink(const sim::Scheduler& scheduler) : scheduler_(scheduler) {}

  void Write(wire::ByteView bytes) override {
    chunks.push_back(Chunk{scheduler_.Now(), std::string(bytes.begin(), bytes.end())});
    pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  }

  // What HostBytesWaiting() answers: a test stands in for a transport
  // with host bytes still in its kernel buffer.
  bool HostBytesWaiting() override { return host_bytes_waiting; }
  bool host_bytes_waiting = false;

  // Everything written, in order, as one string.
  std::string All() const {
    std::string s;
    for (const Chunk& c : chunks) s += c.bytes;
    return s;
  }
  // The bytes written since the last Take().
  const wire::Bytes& bytes() const { return pending_; }
  // Returns the bytes written since the last Take() and forgets them (the
  // chunks are kept).
  wire::Bytes Take() {
    wire::Bytes out;
    out.swap(pending_);
    return out;
  }

  // Every write, oldest first.
  std::vector<Chunk> chunks;

 private:
  const sim::Scheduler& scheduler_;
  wire::Bytes pending_;
};

}  // namespace moco::devices::testing

#endif  // MOCO_DEVICES_TEST_SUPPORT_H_
