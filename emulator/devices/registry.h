// The device models mocosim can emulate, by name ("dmc16", ...), and how to
// build one from its profile (ARCHITECTURE "devices").
#ifndef MOCO_DEVICES_REGISTRY_H_
#define MOCO_DEVICES_REGISTRY_H_

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "devices/device.h"
#include "devices/stackshot3x/state_store.h"
#include "sim/scheduler.h"
#include "wire/transcript.h"

namespace moco::devices {

// Builds a powered-off device of one model (see CreateDevice).
using DeviceFactory = std::unique_ptr<Device> (*)(const std::string& profile_path,
                                                  sim::Scheduler& scheduler, ByteSink& out,
                                                  StateStore* state);

struct DeviceModel {
  std::string_view name;             // "dmc16"
  std::string_view description;      // one line for --help
  wire::Protocol protocol;           // what its serial line speaks
  std::string_view default_profile;  // e.g. "fixtures/profiles/dmc16.json" (informational)
  bool keeps_state = false;          // has NVM kept in a state file (--state)
  DeviceFactory create = nullptr;    // how CreateDevice builds it
};

// Every model, in a stable order.
const std::vector<DeviceModel>& DeviceModels();
// nullptr for an unknown name.
const DeviceModel* FindDeviceModel(std::string_view name);

// Builds a powered-off device of `model` writing to `out`, from the profile
// file at `profile_path` (empty: the model's built-in defaults). Throws
// ProfileError for a bad profile and std::invalid_argument (listing the
// models) for an unknown model. `scheduler` and `out` must outlive the device.
// `state`: where a model that keeps_state keeps its NVM (nullptr: in memory
// only, lost at exit); it must outlive the device. The caller opens the file
// behind it (devices open no files). Ignored by other models.
std::unique_ptr<Device> CreateDevice(std::string_view model, const std::string& profile_path,
                                     sim::Scheduler& scheduler, ByteSink& out,
                                     StateStore* state = nullptr);

}  // namespace moco::devices

#endif  // MOCO_DEVICES_REGISTRY_H_
