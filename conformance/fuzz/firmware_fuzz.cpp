// libFuzzer entry that fuzzes AVR firmware under simavr (fuzz/executor.h), for
// ClusterFuzzLite / OSS-Fuzz on a firmware vendor's repository: an input is a
// host byte stream, cut into messages and played into the firmware, booted
// once and forked per input as `mococheck fuzz --target simavr:` does. The AVR
// program counter's edges of the run are handed to libFuzzer as extra
// coverage counters, so its corpus grows on the firmware's code, not only on
// this harness's. A finding (a broken invariant, a hang, a crash, a stack
// overflow or smash, a division by zero, a reset) aborts with its kind, what
// happened and the firmware's backtrace.
//
// Where the firmware is (docs/firmware-ci.md "ClusterFuzzLite"), from the
// environment, else from KEY=VALUE lines in a file beside this program named as
// it with ".conf" appended ($OUT/firmware_fuzz.conf, where a fuzzing service
// passes no environment):
//   MOCO_FIRMWARE           PATH.elf[@MCU[:HZ]]; in the .conf file relative to
//                           this program's folder (default: firmware_fuzz.elf
//                           beside it)
//   MOCO_FIRMWARE_PROTOCOL  the protocol it speaks (default "dfmoco")
// The custom mutator is the structure-aware one `mococheck fuzz` uses.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

#include "conformance/fuzz/executor.h"
#include "conformance/fuzz/mutator.h"
#include "conformance/targets/simavr_target.h"
#include "wire/protocol.h"

namespace {

using moco::conformance::FuzzExecutor;
using moco::conformance::Messages;
using moco::conformance::Protocol;
using moco::conformance::SessionMutator;

constexpr size_t kEdges = size_t{64} << 10;
constexpr size_t kMaxInput = 64 * 1024;

[[noreturn]] void Die(const std::string& what) {
  std::fprintf(stderr, "firmware_fuzz: %s\n", what.c_str());
  std::abort();
}

std::string Self() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
  if (n <= 0) Die("cannot find this program's path; set MOCO_FIRMWARE=PATH.elf");
  return std::string(self, static_cast<size_t>(n));
}

// `key` from the environment, else from the .conf file beside this program, else "".
std::string Setting(const std::string& key) {
  if (const char* e = std::getenv(key.c_str()); e != nullptr && *e != '\0') return e;
  std::ifstream conf(Self() + ".conf");
  std::string line;
  while (std::getline(conf, line)) {
    if (line.rfind(key + "=", 0) == 0) return line.substr(key.size() + 1);
  }
  return "";
}

Protocol FuzzedProtocol() {
  const std::string name = Setting("MOCO_FIRMWARE_PROTOCOL");
  const std::string text = name.empty() ? "dfmoco" : name;
  const auto p = moco::wire::ParseProtocol(text);
  if (!p) {
    Die("MOCO_FIRMWARE_PROTOCOL=" + text + " names no protocol; give " +
        moco::wire::NameList(moco::conformance::kAllProtocols));
  }
  return *p;
}

std::string FirmwareAddress() {
  if (const char* e = std::getenv("MOCO_FIRMWARE"); e != nullptr && *e != '\0') return e;
  const std::string self = Self();
  const std::string given = Setting("MOCO_FIRMWARE");
  if (given.empty()) return self + ".elf";
  return given[0] == '/' ? given : self.substr(0, self.rfind('/') + 1) + given;
}

const Protocol kProtocol = FuzzedProtocol();

FuzzExecutor& Executor() {
  static FuzzExecutor* executor = [] {
    const std::string address = FirmwareAddress();
    auto spec = moco::conformance::ParseSimavrAddress(address);
    if (const auto* err = std::get_if<std::string>(&spec)) Die("MOCO_FIRMWARE: " + *err);
    FuzzExecutor::Options options;
    options.fork = true;
    options.coverage_bytes = kEdges;
    auto* e = new FuzzExecutor(kProtocol,
                               std::make_unique<moco::conformance::SimavrTarget>(
                                   std::get<moco::conformance::SimavrSpec>(spec)),
                               options);
    if (auto err = e->Open()) Die(*err + " (set MOCO_FIRMWARE=PATH.elf to fuzz another image)");
    if (!e->CanRun()) Die("the protocol's sessions cannot be run against firmware");
    return e;
  }();
  return *executor;
}

}  // namespace

// libFuzzer reads this section after every input as extra coverage counters.
extern "C" {
__attribute__((section("__libfuzzer_extra_counters"))) uint8_t moco_avr_edges[kEdges];
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size > kMaxInput) return -1;
  Messages messages = moco::wire::SplitMessages(kProtocol, moco::wire::Side::kHost, {data, size});
  if (messages.size() > SessionMutator::kMaxMessages) return -1;
  FuzzExecutor& executor = Executor();
  const auto verdict = executor.Run(messages);
  const auto edges = executor.coverage();
  std::memcpy(moco_avr_edges, edges.data(), std::min(edges.size(), kEdges));
  if (!verdict.ok) {
    std::string what = "[" + std::string(moco::conformance::FindingKindName(verdict.kind)) + "] " +
                       verdict.violation;
    for (size_t i = 0; i < verdict.backtrace.size(); ++i) {
      what += (i == 0 ? "\n  at " : "\n  called from ") + verdict.backtrace[i];
    }
    Die(what);
  }
  return 0;
}

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size,
                                          unsigned int seed) {
  return SessionMutator::MutateStream(kProtocol, data, size, max_size, seed);
}
