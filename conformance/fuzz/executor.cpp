// The fuzz executor (see executor.h): what a run plays and judges is the
// protocol's (its FuzzHooks, conformance/protocols/registry.h).
#include "conformance/fuzz/executor.h"

#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>

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
  int64_t simulated_ns;
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

// Writes all of `bytes` to a socket (no SIGPIPE when the other end is gone);
// whether it could.
bool SendAll(int socket, const void* bytes, size_t n) {
  const auto* p = static_cast<const uint8_t*>(bytes);
  while (n > 0) {
    const ssize_t k = send(socket, p, n, MSG_NOSIGNAL);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}

// Reads exactly `n` bytes; false at the end of the stream or an error. A
// signal that interrupts the wait ends it when `give_up_on_stop` and a stop
// was requested.
bool ReceiveAll(int socket, void* bytes, size_t n, bool give_up_on_stop) {
  auto* p = static_cast<uint8_t*>(bytes);
  while (n > 0) {
    const ssize_t k = recv(socket, p, n, 0);
    if (k < 0 && errno == EINTR) {
      if (give_up_on_stop && StopRequested() != 0) return false;
      continue;
    }
    if (k <= 0) return false;
    p += k;
    n -= static_cast<size_t>(k);
  }
  return true;
}

// Messages as bytes: each message's length (4 bytes), then its bytes. A
// prefix's key, and the rest of a session as a snapshot is sent it.
std::string Encode(std::span<const wire::Bytes> messages) {
  std::string out;
  for (const wire::Bytes& m : messages) {
    const auto n = static_cast<uint32_t>(m.size());
    out.append(reinterpret_cast<const char*>(&n), sizeof n);
    out.append(m.begin(), m.end());
  }
  return out;
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
  while (!snapshots_.empty()) Drop(snapshots_.begin());
  if (shared_ != nullptr) munmap(shared_, shared_bytes_);
  if (code_ != nullptr) munmap(code_, code_bytes_);
}

std::optional<std::string> FuzzExecutor::Open() {
  if (!target_->VirtualClock() || !target_->CanRestart()) {
    return target_->Name() +
           " runs in real time or cannot restart; fuzz needs a device in virtual time "
           "(in-process:MODEL, simavr:FIRMWARE.elf or native:FIRMWARE); use replay for a real "
           "device";
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
  if (options_.pins) {
    if (auto err = target_->WatchPins(options_.pins->board)) return err;
  }
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

bool FuzzExecutor::CanRun() const { return hooks_ != nullptr && hooks_->start != nullptr; }

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
  const TimeNs start = target_->Now();
  const std::unique_ptr<FuzzPlay> play = hooks_->start(boot_out, Pins());
  for (const wire::Bytes& m : messages) play->Play(*target_, m);
  return Conclude(*play, start);
}

FuzzVerdict FuzzExecutor::Conclude(FuzzPlay& play, TimeNs start) {
  FuzzVerdict v = play.Finish(*target_);
  v.simulated_ns = target_->Now() - start;
  if (auto fault = target_->FirmwareFaulted()) {
    v.ok = false;
    v.kind = FindingKindOf(fault->kind);
    v.violation = "the firmware stopped: " + fault->what;
    v.backtrace = std::move(fault->backtrace);
  }
  return v;
}

FuzzVerdict FuzzExecutor::Run(const Messages& messages) {
  if (hooks_ == nullptr || hooks_->start == nullptr) {
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

namespace {

// What a forked run writes back into `back`.
void WriteBack(const FuzzVerdict& v, SharedVerdict* back) {
  back->ok = v.ok ? 1 : 0;
  back->kind = static_cast<uint32_t>(v.kind);
  back->messages = v.messages;
  back->replies = v.replies;
  back->simulated_ns = v.simulated_ns;
  back->violation_bytes = CopyOut(v.violation, back->violation, sizeof back->violation);
  std::string frames;
  for (const std::string& f : v.backtrace) frames += f + "\n";
  back->backtrace_bytes = CopyOut(frames, back->backtrace, sizeof back->backtrace);
  back->done = 1;
}

}  // namespace

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
    WriteBack(RunHere(messages, boot_out_), back);
    _exit(0);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return ReadBack(back->done == 1, status, messages.size());
}

FuzzVerdict FuzzExecutor::ReadBack(bool done, int status, size_t messages) {
  const auto* back = reinterpret_cast<const SharedVerdict*>(shared_ + options_.coverage_bytes);
  if (!done) {
    return Violation(
        "mococheck's run process ended without a verdict (" + WaitStatusText(status) + ")",
        messages, 0);
  }
  FuzzVerdict v;
  v.ok = back->ok != 0;
  v.kind = static_cast<FuzzVerdict::Kind>(back->kind);
  v.messages = back->messages;
  v.replies = back->replies;
  v.simulated_ns = back->simulated_ns;
  v.violation.assign(back->violation, back->violation_bytes);
  const std::string frames(back->backtrace, back->backtrace_bytes);
  for (size_t at = 0; at < frames.size();) {
    const size_t nl = std::min(frames.find('\n', at), frames.size());
    v.backtrace.push_back(frames.substr(at, nl - at));
    at = nl + 1;
  }
  return v;
}

FuzzVerdict FuzzExecutor::Run(const Messages& messages, size_t prefix) {
  if (!snapshots() || prefix == 0 || prefix > messages.size() || hooks_ == nullptr ||
      hooks_->start == nullptr) {
    return Run(messages);
  }
  const std::span<const wire::Bytes> all(messages);
  const std::string key = Encode(all.first(prefix));
  Snapshot* snapshot = SnapshotAfter(key, all.first(prefix));
  if (snapshot == nullptr) return Run(messages);
  if (options_.coverage_bytes != 0) std::fill_n(shared_, options_.coverage_bytes, uint8_t{0});
  auto* back = reinterpret_cast<SharedVerdict*>(shared_ + options_.coverage_bytes);
  std::memset(back, 0, sizeof *back);
  // The rest, as the snapshot reads it: its length in bytes, then Encode()d.
  std::string rest = Encode(all.subspan(prefix));
  const auto bytes = static_cast<uint32_t>(rest.size());
  rest.insert(0, reinterpret_cast<const char*>(&bytes), sizeof bytes);
  int32_t status = 0;
  if (!SendAll(snapshot->socket, rest.data(), rest.size()) ||
      !ReceiveAll(snapshot->socket, &status, sizeof status, true)) {
    // The snapshot is gone (killed, or a stop request ended it): run it whole.
    Drop(snapshots_.find(key));
    if (StopRequested() != 0) return ReadBack(false, 0, messages.size());
    return Run(messages);
  }
  return ReadBack(back->done == 1, status, messages.size());
}

FuzzExecutor::Snapshot* FuzzExecutor::SnapshotAfter(const std::string& key,
                                                    std::span<const wire::Bytes> prefix) {
  if (auto at = snapshots_.find(key); at != snapshots_.end()) {
    at->second.used = ++uses_;
    return &at->second;
  }
  while (snapshots_.size() >= options_.snapshots) {
    auto oldest = snapshots_.begin();
    for (auto it = snapshots_.begin(); it != snapshots_.end(); ++it) {
      if (it->second.used < oldest->second.used) oldest = it;
    }
    Drop(oldest);
  }
  int pair[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0) return nullptr;
  const pid_t pid = fork();
  if (pid < 0) {
    close(pair[0]);
    close(pair[1]);
    return nullptr;
  }
  if (pid == 0) {
    close(pair[0]);
    ServeSnapshot(pair[1], prefix);
  }
  close(pair[1]);
  char ready = 0;
  if (!ReceiveAll(pair[0], &ready, 1, true) || ready != 'r') {
    close(pair[0]);
    kill(pid, SIGKILL);
    while (waitpid(pid, nullptr, 0) < 0 && errno == EINTR) {
    }
    return nullptr;
  }
  Snapshot& made = snapshots_[key];
  made = Snapshot{pid, pair[0], ++uses_};
  return &made;
}

// The snapshot's process: plays the prefix once, then for each rest it is
// sent forks a run that plays it and writes its verdict back, and answers
// with the run's wait status. It ends when the executor closes its end (or
// ends itself: PR_SET_PDEATHSIG), or at a stop request while it waits.
void FuzzExecutor::ServeSnapshot(int socket, std::span<const wire::Bytes> prefix) {
  const pid_t executor = getppid();
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != executor) _exit(0);
  // The other snapshots' sockets are the executor's, not this process's: an
  // end held here would keep that snapshot from seeing the executor go.
  for (const auto& [key, other] : snapshots_) close(other.socket);
  const std::unique_ptr<FuzzPlay> play = hooks_->start(boot_out_, Pins());
  for (const wire::Bytes& m : prefix) play->Play(*target_, m);
  const char ready = 'r';
  if (!SendAll(socket, &ready, 1)) _exit(0);
  auto* back = reinterpret_cast<SharedVerdict*>(shared_ + options_.coverage_bytes);
  std::string rest;
  for (;;) {
    uint32_t bytes = 0;
    if (!ReceiveAll(socket, &bytes, sizeof bytes, true)) _exit(0);
    rest.resize(bytes);
    if (!ReceiveAll(socket, rest.data(), bytes, true)) _exit(0);
    const pid_t run = fork();
    if (run == 0) {
      close(socket);
      size_t at = 0;
      auto take = [&](void* to, size_t n) {
        if (at + n > rest.size()) _exit(3);
        if (n == 0) return;  // a pause: an empty message, whose data() may be null
        std::memcpy(to, rest.data() + at, n);
        at += n;
      };
      const TimeNs start = target_->Now();
      while (at < rest.size()) {
        uint32_t n = 0;
        take(&n, sizeof n);
        wire::Bytes m(n);
        take(m.data(), n);
        play->Play(*target_, m);
      }
      WriteBack(Conclude(*play, start), back);
      _exit(0);
    }
    int status = 0;
    if (run < 0) {
      status = -1;
    } else {
      while (waitpid(run, &status, 0) < 0 && errno == EINTR) {
      }
    }
    const auto answer = static_cast<int32_t>(status);
    if (!SendAll(socket, &answer, sizeof answer)) _exit(0);
  }
}

void FuzzExecutor::Drop(std::map<std::string, Snapshot>::iterator at) {
  if (at == snapshots_.end()) return;
  close(at->second.socket);
  kill(at->second.pid, SIGKILL);
  while (waitpid(at->second.pid, nullptr, 0) < 0 && errno == EINTR) {
  }
  snapshots_.erase(at);
}

}  // namespace moco::conformance
