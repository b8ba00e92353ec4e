// Test fakes for the control tests: a device on the Device boundary
// (devices/device.h) that owns a rig and a GIO port and records what the
// control channel did to it.
#ifndef MOCO_CONTROL_TEST_SUPPORT_H_
#define MOCO_CONTROL_TEST_SUPPORT_H_

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "devices/device.h"
#include "sim/io.h"
#include "sim/rig.h"
#include "sim/scheduler.h"

namespace moco::control::testing {

// A device with `motors` motors, `limit_sets` limit sets and 32 GIO inputs
// (debounced for 5 ms). Records power calls, e-stop changes and limit trips
// with their scheduler times.
class FakeDevice final : public devices::Device, private sim::RigObserver {
 public:
  static constexpr sim::TimeNs kDebounceNs = 5 * sim::kNsPerMs;

  struct Trip {
    int motor;
    sim::LimitEnd end;
    int set;
    sim::SwitchInput input;
  };

  FakeDevice(sim::Scheduler& scheduler, int motors = 3, int limit_sets = 2,
             std::string model = "fake")
      : scheduler_(scheduler),
        model_(std::move(model)),
        rig_(scheduler, motors, limit_sets, this),
        gio_(scheduler, kDebounceNs) {}

  std::string_view Model() const override { return model_; }
  devices::DeviceLine Line() const override { return {}; }
  void PowerOn() override {
    powered_ = true;
    power_on_ns.push_back(scheduler_.Now());
  }
  void PowerOff() override {
    powered_ = false;
    power_off_ns.push_back(scheduler_.Now());
  }
  bool Powered() const override { return powered_; }
  void OnHostBytes(wire::ByteView bytes) override {
    if (powered_) host_bytes += bytes.size();
  }
  sim::Rig* rig() override { return &rig_; }
  sim::GioPort* gio() override { return &gio_; }
  nlohmann::json State() const override {
    return {{"mode", "idle"}, {"power_ons", power_on_ns.size()}};
  }

  // Reports an event as a device does by itself (a stall, a collision).
  void Emit(const nlohmann::json& event) const { EmitEvent(event); }

  sim::Rig& the_rig() { return rig_; }
  sim::GioPort& the_gio() { return gio_; }

  std::vector<sim::TimeNs> power_on_ns;
  std::vector<sim::TimeNs> power_off_ns;
  std::vector<bool> estop_events;
  std::vector<Trip> trips;
  size_t host_bytes = 0;

 private:
  void OnLimitTripped(int motor_id, sim::LimitEnd end, int set, sim::SwitchInput input, sim::TimeNs,
                      int64_t) override {
    trips.push_back({motor_id, end, set, input});
  }
  void OnEStop(bool engaged, sim::TimeNs) override { estop_events.push_back(engaged); }

  sim::Scheduler& scheduler_;
  std::string model_;
  sim::Rig rig_;
  sim::GioPort gio_;
  bool powered_ = false;
};

// A device with neither rig nor GIO (a camera trigger, say).
class BareDevice final : public devices::Device {
 public:
  std::string_view Model() const override { return "bare"; }
  devices::DeviceLine Line() const override { return {}; }
  void PowerOn() override { powered_ = true; }
  void PowerOff() override { powered_ = false; }
  bool Powered() const override { return powered_; }
  void OnHostBytes(wire::ByteView) override {}

 private:
  bool powered_ = false;
};

}  // namespace moco::control::testing

#endif  // MOCO_CONTROL_TEST_SUPPORT_H_
