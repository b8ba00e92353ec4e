// The fuzz executor (see executor.h): what a run plays and judges is the
// protocol's (its FuzzHooks, conformance/protocols/registry.h).
#include "conformance/fuzz/executor.h"

#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "conformance/protocols/registry.h"

namespace moco::conformance {
namespace {

// What a forked child writes back after the coverage map.
struct SharedVerdict {
  uint32_t done;  // 1 once the rest is written
  uint32_t ok;
  uint32_t kind;
  uint32_t violation_bytes;
  uint64_t messages;
  uint64_t replies;
  uint32_t backtrace_bytes;  // the frames, one per line
  char violation[4096];
  char backtrace[2048];
};

// Copies as much of `text` as fits into `to`; the bytes copied.
uint32_t CopyOut(const std::string& text, char* to, size_t room) {
  const size_t n = std::min(text.size(), room);
  std::memcpy(to, text.data(), n);
  return static_cast<uint32_t>(n);
}

std::string WaitStatusText(int status) {
  if (WIFSIGNALED(status)) {
    return "killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
           strsignal(WTERMSIG(status)) + ")";
  }
  if (WIFEXITED(status)) return "exit status " + std::to_string(WEXITSTATUS(status));
  return "status " + std::to_string(status);
}

}  // namespace

FuzzExecutor::FuzzExecutor(Protocol protocol, std::unique_ptr<Target> target)
    : FuzzExecutor(protocol, std::move(target), Options()) {}

FuzzExecutor::FuzzExecutor(Protocol protocol, std::unique_ptr<Target> target, Options options)
    : protocol_(protocol),
      hooks_(FindFuzzHooks(protocol)),
      target_(std::move(target)),
      options_(options) {}

FuzzExecutor::~FuzzExecutor() {
  if (shared_ != nullptr) munmap(shared_, shared_bytes_);
  if (code_ != nullptr) munmap(code_, code_bytes_);
}

std::optional<std::string> FuzzExecutor::Open() {
  if (!target_->VirtualClock() || !target_->CanRestart()) {
    return target_->Name() +
           " runs in real time or cannot restart; fuzz needs a device in virtual time "
           "(in-process:MODEL or simavr:FIRMWARE.elf); use replay for a real device";
  }
  const size_t map = options_.coverage_bytes;
  if (map != 0 && (map & (map - 1)) != 0) {
    return "the coverage map's size " + std::to_string(map) + " is not a power of two";
  }
  if (map != 0 || options_.fork) {
    shared_bytes_ = map + sizeof(SharedVerdict);
    void* p =
        mmap(nullptr, shared_bytes_, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) {
      shared_bytes_ = 0;
      return std::string("cannot map the fuzzer's shared memory: ") + std::strerror(errno);
    }
    shared_ = static_cast<uint8_t*>(p);
  }
  // Every fault a firmware can show is a finding here, whatever it costs per
  // instruction (a target without firmware watches nothing).
  target_->WatchFirmwareFaults();
  if (auto err = target_->Open()) return err;
  if (map != 0 && !target_->SetCoverageMap(shared_, map)) {
    return target_->Name() +
           " cannot observe its device's code: no coverage (fuzz it without "
           "coverage, or run its firmware under simavr)";
  }
  if (const size_t code = target_->InstructionMapBytes(); map != 0 && code != 0) {
    void* p = mmap(nullptr, code, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) {
      return std::string("cannot map the fuzzer's shared memory: ") + std::strerror(errno);
    }
    code_ = static_cast<uint8_t*>(p);
    code_bytes_ = code;
    target_->SetInstructionMap(code_, code_bytes_);
  }
  if (options_.fork) {
    target_->Restart();
    boot_out_.clear();
    if (hooks_ != nullptr && hooks_->boot != nullptr) hooks_->boot(*target_, boot_out_);
    if (auto why = target_->FirmwareStopped()) {
      return "the firmware stopped while it booted: " + *why;
    }
  }
  return std::nullopt;
}

bool FuzzExecutor::CanRun() const { return hooks_ != nullptr && hooks_->run != nullptr; }

TimeNs FuzzExecutor::gap_ns() const { return hooks_ == nullptr ? 0 : hooks_->gap_ns; }

std::span<const uint8_t> FuzzExecutor::coverage() const {
  if (shared_ == nullptr || options_.coverage_bytes == 0) return {};
  return {shared_, options_.coverage_bytes};
}

std::optional<CodeCoverage> FuzzExecutor::code_coverage() const {
  if (code_ == nullptr) return std::nullopt;
  return target_->CodeCoverageOf({code_, code_bytes_});
}

std::string FuzzExecutor::target_name() const { return target_->Name(); }

FuzzVerdict FuzzExecutor::RunHere(const Messages& messages, const wire::Bytes& boot_out) {
  FuzzVerdict v = hooks_->run(*target_, messages, gap_ns(), boot_out);
  if (auto fault = target_->FirmwareFaulted()) {
    v.ok = false;
    v.kind = FindingKindOf(fault->kind);
    v.violation = "the firmware stopped: " + fault->what;
    v.backtrace = std::move(fault->backtrace);
  }
  return v;
}

FuzzVerdict FuzzExecutor::Run(const Messages& messages) {
  if (hooks_ == nullptr || hooks_->run == nullptr) {
    return Violation("the " + std::string(wire::Info(protocol_).title) + " protocol is not fuzzed",
                     0, 0);
  }
  if (options_.coverage_bytes != 0) std::fill_n(shared_, options_.coverage_bytes, uint8_t{0});
  if (options_.fork) return RunForked(messages);
  target_->Restart();
  wire::Bytes boot_out;
  if (hooks_->boot != nullptr) hooks_->boot(*target_, boot_out);
  return RunHere(messages, boot_out);
}

FuzzVerdict FuzzExecutor::RunForked(const Messages& messages) {
  auto* back = reinterpret_cast<SharedVerdict*>(shared_ + options_.coverage_bytes);
  std::memset(back, 0, sizeof *back);
  const pid_t pid = fork();
  if (pid < 0) {
    return Violation(std::string("mococheck could not fork a run: ") + std::strerror(errno),
                     messages.size(), 0);
  }
  if (pid == 0) {
    // The child: plays from the booted state, writes the verdict back and
    // leaves without running any exit handler of the parent's.
    const FuzzVerdict v = RunHere(messages, boot_out_);
    back->ok = v.ok ? 1 : 0;
    back->kind = static_cast<uint32_t>(v.kind);
    back->messages = v.messages;
    back->replies = v.replies;
    back->violation_bytes = CopyOut(v.violation, back->violation, sizeof back->violation);
    std::string frames;
    for (const std::string& f : v.backtrace) frames += f + "\n";
    back->backtrace_bytes = CopyOut(frames, back->backtrace, sizeof back->backtrace);
    back->done = 1;
    _exit(0);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (back->done != 1) {
    return Violation(
        "mococheck's run process ended without a verdict (" + WaitStatusText(status) + ")",
        messages.size(), 0);
  }
  FuzzVerdict v;
  v.ok = back->ok != 0;
  v.kind = static_cast<FuzzVerdict::Kind>(back->kind);
  v.messages = back->messages;
  v.replies = back->replies;
  v.violation.assign(back->violation, back->violation_bytes);
  const std::string frames(back->backtrace, back->backtrace_bytes);
  for (size_t at = 0; at < frames.size();) {
    const size_t nl = std::min(frames.find('\n', at), frames.size());
    v.backtrace.push_back(frames.substr(at, nl - at));
    at = nl + 1;
  }
  return v;
}

}  // namespace moco::conformance
