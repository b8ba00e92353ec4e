// SIGINT, SIGTERM and SIGHUP during `mococheck run` and `mococheck fuzz` (see
// commands.h InstallStopHandlers).
#include <atomic>
#include <csignal>

#include "conformance/cli/commands.h"

namespace moco::conformance::cli {
namespace {

std::atomic<int> g_signals_seen{0};

extern "C" void OnStopSignal(int sig) {
  if (g_signals_seen.fetch_add(1) >= 2) {
    std::signal(sig, SIG_DFL);
    std::raise(sig);
    return;
  }
  if (StopRequested() == 0) RequestStop(sig);
}

}  // namespace

void InstallStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = OnStopSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a waiting poll() returns EINTR and sees the request
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) sigaction(sig, &sa, nullptr);
}

}  // namespace moco::conformance::cli
