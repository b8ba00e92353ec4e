// The device models by name (see registry.h).
#include "devices/registry.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "devices/dfmoco_arduino/dfmoco_arduino.h"
#include "devices/dmc16/dmc16.h"
#include "devices/stackshot3x/stackshot3x.h"

namespace moco::devices {

namespace {

// One factory per model: reads the profile file (empty: the built-in
// defaults) once, then makes devices from it.
DeviceMaker MakeDmc16(const std::string& profile_path) {
  Dmc16Profile profile = profile_path.empty() ? Dmc16Profile{} : LoadDmc16Profile(profile_path);
  return [profile = std::move(profile)](sim::Scheduler& scheduler, ByteSink& out,
                                        StateStore* /*state*/, const DeviceStart& /*start*/) {
    return std::unique_ptr<Device>(std::make_unique<Dmc16>(scheduler, out, profile));
  };
}

DeviceMaker MakeDfmoco(const std::string& profile_path) {
  DfmocoProfile profile = profile_path.empty() ? DfmocoProfile{} : LoadDfmocoProfile(profile_path);
  return [profile = std::move(profile)](sim::Scheduler& scheduler, ByteSink& out,
                                        StateStore* /*state*/, const DeviceStart& /*start*/) {
    return std::unique_ptr<Device>(std::make_unique<DfmocoArduino>(scheduler, out, profile));
  };
}

DeviceMaker MakeStackshot3x(const std::string& profile_path) {
  Stackshot3xProfile profile =
      profile_path.empty() ? Stackshot3xProfile{} : LoadStackshot3xProfile(profile_path);
  return [profile = std::move(profile)](sim::Scheduler& scheduler, ByteSink& out, StateStore* state,
                                        const DeviceStart& start) {
    auto device = std::make_unique<Stackshot3x>(scheduler, out, profile, state);
    if (start.speaking == wire::Protocol::kStackshotDfmoco) {
      // Settings->Mode->Motion->DfMoco on the panel (stackshot-protocol.txt
      // section 3) is kept in NVM as the power-on mode.
      device->SetPowerOnMode(stackshot::GlobalMode::kMotionDfMoco);
    }
    return std::unique_ptr<Device>(std::move(device));
  };
}

// A StackShot 3X in DfMoco mode speaks DFMoco lines on its USB port.
constexpr wire::Protocol kStackshot3xAlso[] = {wire::Protocol::kStackshotDfmoco};

}  // namespace

const std::vector<DeviceModel>& DeviceModels() {
  static const std::vector<DeviceModel> kModels = {
      {"dmc16", "DMC-16 motion controller, DMC v2 binary protocol", wire::Protocol::kDmc,
       "fixtures/profiles/dmc16.json", false, &MakeDmc16},
      {"dfmoco", "DFMoco Arduino (Uno or Mega), Dragonframe's ASCII sketch protocol",
       wire::Protocol::kDfmoco, "fixtures/profiles/dfmoco-uno.json", false, &MakeDfmoco},
      {"stackshot3x", "Cognisys StackShot 3X three-axis controller, StackShot binary protocol",
       wire::Protocol::kStackshot, "fixtures/profiles/stackshot3x.json", true, &MakeStackshot3x,
       kStackshot3xAlso, /*wifi=*/true},
  };
  return kModels;
}

const DeviceModel* FindDeviceModel(std::string_view name) {
  for (const DeviceModel& m : DeviceModels()) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

std::optional<wire::Protocol> LineFor(const DeviceModel& model, wire::Protocol host) {
  auto serves = [host](wire::Protocol line) {
    return line == host || wire::Info(line).dialect_of == host;
  };
  if (serves(model.protocol)) return model.protocol;
  for (const wire::Protocol p : model.also_speaks) {
    if (serves(p)) return p;
  }
  return std::nullopt;
}

std::string SpokenNames(const DeviceModel& model) {
  std::vector<wire::Protocol> all{model.protocol};
  all.insert(all.end(), model.also_speaks.begin(), model.also_speaks.end());
  return wire::NameList(all);
}

DeviceMaker PrepareDevice(std::string_view model, const std::string& profile_path,
                          const DeviceStart& start) {
  if (const DeviceModel* m = FindDeviceModel(model)) {
    if (start.speaking && *start.speaking != m->protocol &&
        std::find(m->also_speaks.begin(), m->also_speaks.end(), *start.speaking) ==
            m->also_speaks.end()) {
      throw std::invalid_argument(std::string(m->name) + " does not speak " +
                                  std::string(wire::ProtocolName(*start.speaking)) +
                                  "; it speaks " + SpokenNames(*m));
    }
    return m->create(profile_path);
  }
  std::string known;
  for (const DeviceModel& m : DeviceModels()) {
    if (!known.empty()) known += ", ";
    known += m.name;
  }
  throw std::invalid_argument("unknown device model \"" + std::string(model) +
                              "\"; the models are: " + known);
}

std::unique_ptr<Device> CreateDevice(std::string_view model, const std::string& profile_path,
                                     sim::Scheduler& scheduler, ByteSink& out, StateStore* state,
                                     const DeviceStart& start) {
  return PrepareDevice(model, profile_path, start)(scheduler, out, state, start);
}

}  // namespace moco::devices
