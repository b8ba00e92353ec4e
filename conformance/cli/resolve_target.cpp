// From a --target text to a target (see commands.h): the one place the three
// commands that talk to a device pick it.
#include <iostream>

#include "conformance/cli/commands.h"
#include "devices/registry.h"

namespace moco::conformance::cli {
namespace {

// The device model a session names ("dfmoco-uno" -> "dfmoco"), if registered.
std::string ModelOfSessionDevice(const std::string& device) {
  for (const auto& m : devices::DeviceModels()) {
    if (device == m.name || device.rfind(std::string(m.name) + "-", 0) == 0) {
      return std::string(m.name);
    }
  }
  return "";
}

std::string KnownModels() {
  std::string known;
  for (const auto& m : devices::DeviceModels()) {
    known += (known.empty() ? "" : ", ") + std::string(m.name);
  }
  return known;
}

}  // namespace

int Fail(const std::string& message) {
  std::cerr << "mococheck: " << message << "\n";
  return kExitUsage;
}

std::variant<ResolvedTarget, std::string> ResolveTarget(const TargetRequest& request) {
  std::string text = request.text;
  if (text.empty()) {
    const std::string model = ModelOfSessionDevice(request.session_device);
    if (model.empty()) return request.no_device_message;
    text = "in-process:" + model;
  }
  const auto spec = ParseTargetSpec(text);
  if (const auto* err = std::get_if<std::string>(&spec)) return *err;
  ResolvedTarget out;
  out.spec = std::get<TargetSpec>(spec);
  const TargetSpec& ts = out.spec;
  const bool in_process = ts.kind == TargetSpec::Kind::kInProcess;
  if (!request.virtual_clock_only_message.empty() && !in_process &&
      ts.kind != TargetSpec::Kind::kSimavr && ts.kind != TargetSpec::Kind::kNative) {
    return request.virtual_clock_only_message;
  }
  const devices::DeviceModel* model = in_process ? devices::FindDeviceModel(ts.address) : nullptr;
  if (in_process && model == nullptr) {
    return "unknown in-process model \"" + ts.address + "\"; the models are: " + KnownModels();
  }

  // The protocol: the traffic's, else as given, else the in-process model's,
  // else DMC v2. An in-process model may start speaking another protocol it
  // also speaks (the registry's also_speaks: a StackShot 3X in DfMoco mode
  // for DFMoco traffic, stackshot-protocol.txt section 3).
  if (request.protocol) {
    out.protocol = *request.protocol;
    if (model != nullptr && !devices::LineFor(*model, out.protocol)) {
      return "in-process:" + ts.address + " does not speak " + request.traffic_name + " protocol " +
             std::string(ProtocolName(out.protocol));
    }
  } else if (!request.protocol_option.empty()) {
    const auto p = wire::ParseProtocolOrAlias(request.protocol_option);
    if (!p) {
      return "--protocol " + request.protocol_option + ": give " + wire::NameList(kAllProtocols);
    }
    if (model != nullptr && !devices::LineFor(*model, *p)) {
      return "--protocol " + request.protocol_option + " does not match in-process:" + ts.address +
             ", which speaks " + devices::SpokenNames(*model) +
             "; drop --protocol or pick the matching model";
    }
    out.protocol = *p;
  } else if (model != nullptr) {
    out.protocol = model->protocol;
  }
  if (model != nullptr) {
    const wire::Protocol line = *devices::LineFor(*model, out.protocol);
    if (line != model->protocol) out.speaking = line;
  }

  if (!request.profile.empty() && !in_process) {
    return "--profile applies to in-process targets only; an external device has its own";
  }
  if (out.speaking) {
    out.target = InProcessTarget::ForModel(ts.address, request.profile, out.speaking);
    return out;
  }
  auto made = MakeTarget(ts, request.profile,
                         request.baud ? request.baud : wire::Info(out.protocol).line.baud);
  if (const auto* err = std::get_if<std::string>(&made)) return *err;
  out.target = std::move(std::get<std::unique_ptr<Target>>(made));
  return out;
}

}  // namespace moco::conformance::cli
