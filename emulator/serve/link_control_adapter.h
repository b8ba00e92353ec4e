// The control channel's view of a served device's link (control::LinkControl)
// over the transport's DeviceServer: the one place where the two meet.
#ifndef MOCO_SERVE_LINK_CONTROL_ADAPTER_H_
#define MOCO_SERVE_LINK_CONTROL_ADAPTER_H_

#include <string>

#include "control/link_control.h"
#include "sim/line_faults.h"
#include "sim/scheduler.h"
#include "transport/device_server.h"

namespace moco::serve {

// Typical use:
//   DeviceServerLink link(server);
//   channel.AddDevice("dmc16", device, &link);
// The server must outlive the adapter.
class DeviceServerLink final : public control::LinkControl {
 public:
  explicit DeviceServerLink(transport::DeviceServer& server) : server_(server) {}

  std::string Where() const override { return server_.Where(); }
  void CutLink(sim::TimeNs duration_ns) override { server_.CutLink(duration_ns); }
  void PowerCycle(sim::TimeNs off_ns) override { server_.PowerCycle(off_ns); }
  void SetFaults(const sim::FaultConfig& config) override { server_.link().SetFaults(config); }
  control::LinkStatus Status() override;

 private:
  transport::DeviceServer& server_;
};

}  // namespace moco::serve

#endif  // MOCO_SERVE_LINK_CONTROL_ADAPTER_H_
