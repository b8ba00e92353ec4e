// StackShot 3X for the runner (see stackshot_protocol.h).
#include "conformance/protocols/stackshot/stackshot_protocol.h"

#include "base/format.h"

#include <cstdio>
#include <string>
#include <utility>

namespace moco::conformance {
namespace {}  // namespace

std::optional<SsDeviceInfo> StackshotProtocol::Discover(SsHost& probe) {
  // Asked twice, as a host does after its answer timeout.
  for (int attempt = 0; attempt < 2 && !probe.link_lost(); ++attempt) {
    SsDeviceInfo d = DiscoverStackshot(probe);
    if (d.answered) return d;
  }
  return std::nullopt;
}

void StackshotProtocol::Describe(const SsDeviceInfo& d, RunReport& report) {
  const std::string name = d.software_string.value_or("(no software string)");
  report.device = "\"" + name + "\"";
  report.device_info = {{"software_string", name}, {"axes", d.three_axes ? 3 : 1}};
  const std::pair<const char*, std::optional<uint32_t>> ids[] = {
      {"software_id", d.software_id},
      {"hardware_id", d.hardware_id},
      {"bootloader_id", d.bootloader_id},
      {"serial_number", d.serial_number}};
  for (const auto& [key, value] : ids) {
    if (!value) continue;
    report.device_info[key] = *value;
    report.device += std::string(", ") + key + " " + base::Hex(*value, 8);
  }
  report.device += d.three_axes ? ", axes X Y Z" : ", one axis";
}

std::optional<SsDeviceInfo> StackshotProtocol::Greet(SsHost& host, Target& /*target*/,
                                                     const SsDeviceInfo& discovered) {
  const SsRecord* hello =
      host.Call(SsRead(stackshot::Command::kPing, stackshot::PingRequest{0x5a}));
  if (StatusOf(hello) != stackshot::Action::kRspOk) return std::nullopt;
  return discovered;
}

}  // namespace moco::conformance
