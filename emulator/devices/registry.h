// The device models mocosim can emulate, by name ("dmc16", ...), and how to
// build one from its profile (ARCHITECTURE "devices").
#ifndef MOCO_DEVICES_REGISTRY_H_
#define MOCO_DEVICES_REGISTRY_H_

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "devices/device.h"
#include "devices/stackshot3x/state_store.h"
#include "sim/scheduler.h"
#include "wire/transcript.h"

namespace moco::devices {

// How a device starts out (see CreateDevice).
struct DeviceStart {
  // The protocol its line speaks from power-on: nullopt (or the model's own
  // protocol) for the model's own, else one of the model's also_speaks. The
  // model keeps it as a real unit would (a StackShot 3X: its power-on mode
  // in NVM, stackshot-protocol.txt section 3).
  std::optional<wire::Protocol> speaking;
};

// Builds a powered-off device of one model from a profile already read (see
// PrepareDevice), as often as it is called.
using DeviceMaker = std::function<std::unique_ptr<Device>(
    sim::Scheduler& scheduler, ByteSink& out, StateStore* state, const DeviceStart& start)>;
// Reads one model's profile file (empty: the built-in defaults) and returns
// the maker of its devices (see CreateDevice).
using DeviceFactory = DeviceMaker (*)(const std::string& profile_path);

struct DeviceModel {
  std::string_view name;             // "dmc16"
  std::string_view description;      // one line for --help
  wire::Protocol protocol;           // what its serial line speaks
  std::string_view default_profile;  // e.g. "fixtures/profiles/dmc16.json" (informational)
  bool keeps_state = false;          // has NVM kept in a state file (--state)
  DeviceFactory create = nullptr;    // how CreateDevice builds it
  // The protocols its line can switch to besides `protocol` (by a message,
  // its panel or the mode it powers on in; Device::SetLineSwitchListener
  // announces each switch), and that DeviceStart::speaking can start it in.
  std::span<const wire::Protocol> also_speaks = {};
  bool wifi = false;  // can be served over Wi-Fi (mocosim --wifi)
};

// Every model, in a stable order.
const std::vector<DeviceModel>& DeviceModels();
// nullptr for an unknown name.
const DeviceModel* FindDeviceModel(std::string_view name);

// The protocol `model`'s line starts in for a host speaking `host`: the
// model's own protocol or one of also_speaks that is `host` or a dialect of
// it (wire::ProtocolInfo::dialect_of: a StackShot 3X in DfMoco mode for a
// DFMoco host); nullopt when the model does not speak it.
std::optional<wire::Protocol> LineFor(const DeviceModel& model, wire::Protocol host);
// Every protocol `model` speaks, its own first ("stackshot or stackshot-dfmoco").
std::string SpokenNames(const DeviceModel& model);

// Builds a powered-off device of `model` writing to `out`, from the profile
// file at `profile_path` (empty: the model's built-in defaults). Throws
// ProfileError for a bad profile and std::invalid_argument (listing the
// models) for an unknown model. `scheduler` and `out` must outlive the device.
// `state`: where a model that keeps_state keeps its NVM (nullptr: in memory
// only, lost at exit); it must outlive the device. The caller opens the file
// behind it (devices open no files). Ignored by other models. `start`: how
// it starts out; std::invalid_argument for a protocol the model does not
// speak.
// PrepareDevice then the maker, once. A caller that builds the device again
// (a power cycle) calls PrepareDevice once and the maker each time, so the
// profile file is read once and a file changed meanwhile changes nothing.
DeviceMaker PrepareDevice(std::string_view model, const std::string& profile_path,
                          const DeviceStart& start = {});
std::unique_ptr<Device> CreateDevice(std::string_view model, const std::string& profile_path,
                                     sim::Scheduler& scheduler, ByteSink& out,
                                     StateStore* state = nullptr, const DeviceStart& start = {});

}  // namespace moco::devices

#endif  // MOCO_DEVICES_REGISTRY_H_
