// Test fakes for the transport tests: an echo device on the Device boundary
// (devices/device.h) and a loop that runs an io_context until a condition.
#ifndef MOCO_TRANSPORT_TEST_SUPPORT_H_
#define MOCO_TRANSPORT_TEST_SUPPORT_H_

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "devices/device.h"
#include "transport/asio.h"
#include "wire/dmc_constants.h"

namespace moco::transport::testing {

// Echoes every host byte back (when echo is on) and records what it saw.
class EchoDevice final : public devices::Device {
 public:
  // At a DMC v2 device's line unless told otherwise.
  explicit EchoDevice(devices::ByteSink& sink, uint32_t baud = dmc::kBaudRate) : sink_(sink) {
    line_.serial.baud = baud;
  }
  std::string_view Model() const override { return "echo"; }
  devices::DeviceLine Line() const override { return line_; }
  void PowerOn() override {
    powered_ = true;
    ++power_ons;
  }
  void PowerOff() override {
    powered_ = false;
    ++power_offs;
  }
  bool Powered() const override { return powered_; }
  void OnHostBytes(wire::ByteView bytes) override {
    if (!powered_) return;
    received.insert(received.end(), bytes.begin(), bytes.end());
    if (echo) sink_.Write(bytes);
  }
  void OnHostLink(bool open) override { link_events.push_back(open); }
  // Before the link reads it (Link::SetDevice).
  void SetLine(const devices::DeviceLine& line) { line_ = line; }
  // The line changes to `protocol` on `line` from the next byte on, announced
  // as a device announces it.
  void SwitchLine(wire::Protocol protocol, const devices::DeviceLine& line) {
    line_ = line;
    AnnounceLineSwitch(protocol);
  }
  // Writes as the device (from the io thread).
  void Send(std::string_view text) {
    sink_.Write(wire::ByteView(reinterpret_cast<const uint8_t*>(text.data()), text.size()));
  }

  bool echo = true;
  std::string received;
  std::vector<bool> link_events;
  int power_ons = 0;
  int power_offs = 0;

 private:
  devices::ByteSink& sink_;
  devices::DeviceLine line_;
  bool powered_ = false;
};

// Runs handlers until done() or the deadline (generous: a loaded machine).
// Returns done(). Never sleeps: it waits in the io_context for the next event.
inline bool RunUntil(asio::io_context& io, const std::function<bool()>& done,
                     std::chrono::milliseconds deadline = std::chrono::milliseconds(5000)) {
  const auto end = std::chrono::steady_clock::now() + deadline;
  while (!done()) {
    if (std::chrono::steady_clock::now() >= end) return done();
    io.restart();
    io.run_one_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace moco::transport::testing

#endif  // MOCO_TRANSPORT_TEST_SUPPORT_H_
