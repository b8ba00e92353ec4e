// Firmware built for the host Arduino core as a conformance target
// (native_target.h; the link: conformance/arduino/link.h).
#include "conformance/targets/native_target.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

extern char** environ;

namespace moco::conformance {
namespace lk = arduino::link;

namespace {
// The names of link::Port in an address, by value.
constexpr const char* kPortNames[] = {"serial", "serial1", "serial2", "bluetooth"};
}  // namespace

std::variant<NativeSpec, std::string> ParseNativeAddress(std::string_view address) {
  const std::string usage =
      "; give native:PATH, optionally @serial, @serial1, @serial2 or @bluetooth (the sketch's "
      "port that speaks the protocol), e.g. native:./build/fw@bluetooth";
  NativeSpec spec;
  const size_t at = address.rfind('@');
  spec.path = std::string(address.substr(0, at));
  if (spec.path.empty()) return "no firmware executable path" + usage;
  if (at == std::string_view::npos) return spec;
  const std::string_view port = address.substr(at + 1);
  for (size_t i = 0; i < std::size(kPortNames); ++i) {
    if (port == kPortNames[i]) {
      spec.port = static_cast<lk::Port>(i);
      return spec;
    }
  }
  return "unknown port \"" + std::string(port) + "\"" + usage;
}

NativeTarget::NativeTarget(NativeSpec spec) : spec_(std::move(spec)) {}

NativeTarget::~NativeTarget() { Teardown(); }

std::string NativeTarget::Name() const {
  std::string name = "native:" + spec_.path;
  if (spec_.port != lk::Port::kSerial) {
    name += std::string("@") + kPortNames[static_cast<int>(spec_.port)];
  }
  if (!board_name_.empty()) name += " (board " + board_name_ + ")";
  if (!stopped_.empty()) name += " (firmware stopped: " + stopped_ + ")";
  return name;
}

std::optional<std::string> NativeTarget::Open() {
  Teardown();
  struct stat st {};
  if (stat(spec_.path.c_str(), &st) != 0) {
    return "the firmware " + spec_.path + " cannot be read: " + std::strerror(errno) +
           "; build it with mococheck-build-native (docs/firmware-ci.md) and give its path";
  }
  if (!S_ISREG(st.st_mode)) {
    return "the firmware " + spec_.path +
           " is not a regular file; give the executable mococheck-build-native wrote";
  }
  if (access(spec_.path.c_str(), X_OK) != 0) {
    return "the firmware " + spec_.path + " is not executable; chmod +x it, or build it again";
  }
  return Start();
}

std::optional<std::string> NativeTarget::Start() {
  now_ns_ = 0;
  line_free_ns_ = 0;
  frame_ns_ = 0;
  pending_.clear();
  stopped_.clear();
  stop_kind_ = FirmwareFaultKind::kCrash;
  dropped_ = 0;
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) != 0) {
    return std::string("cannot make the firmware's link: ") + std::strerror(errno);
  }
  // Everything the child needs is made before the fork: between fork and exec
  // it only calls what is safe there (no allocation).
  const std::string path = spec_.path;
  const std::string link_env = std::string(lk::kLinkEnv) + "=1";
  std::vector<char*> envp;
  for (char** e = environ; *e != nullptr; ++e) envp.push_back(*e);
  envp.push_back(const_cast<char*>(link_env.c_str()));
  envp.push_back(nullptr);
  char* const argv[] = {const_cast<char*>(path.c_str()), nullptr};
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    return std::string("cannot start the firmware: ") + std::strerror(errno);
  }
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (fds[1] == lk::kLinkFd) {
      fcntl(lk::kLinkFd, F_SETFD, 0);  // already in place: keep it across exec
    } else {
      dup2(fds[1], lk::kLinkFd);  // the duplicate is inherited: no close-on-exec
    }
    const int null = open("/dev/null", O_RDWR | O_CLOEXEC);
    if (null >= 0) {
      dup2(null, 0);
      dup2(null, 1);
    }
    execve(path.c_str(), argv, envp.data());
    _exit(127);
  }
  close(fds[1]);
  pid_ = pid;
  fd_ = fds[0];

  size_t size = 0;
  if (!ReadPacket(size) || size == 0 || rx_packet_[0] != static_cast<uint8_t>(lk::Type::kHello)) {
    const std::string why = stopped_.empty() ? Ended() : stopped_;
    Teardown();
    return "the firmware " + spec_.path +
           " did not introduce itself as firmware built for the native target (" + why +
           "); build it with mococheck-build-native (docs/firmware-ci.md)";
  }
  lk::Reader r(rx_packet_.data() + 1, size - 1);
  const uint64_t version = r.Get(4);
  if (version != lk::kLinkVersion) {
    Teardown();
    return "the firmware " + spec_.path + " was built against another version of the host core (" +
           std::to_string(version) + ", this mococheck speaks " + std::to_string(lk::kLinkVersion) +
           "); build it again with this mococheck";
  }
  const size_t name_length = r.Get(1);
  board_name_.clear();
  for (size_t i = 0; i < name_length; ++i) board_name_ += static_cast<char>(r.Get(1));
  port_map_.clear();
  const size_t ports = r.Get(2);
  for (size_t i = 0; i < ports && !r.bad; ++i) {
    const int pin = static_cast<int>(r.Get(2));
    const char port = static_cast<char>(r.Get(1));
    const auto bit = static_cast<uint8_t>(r.Get(1));
    port_map_[{port, bit}] = pin;
  }

  std::vector<uint8_t> attach{static_cast<uint8_t>(lk::Type::kAttach),
                              static_cast<uint8_t>(spec_.port)};
  signal_of_pin_.clear();
  if (watching_) {
    trace_ = PinTrace::For(watched_board_);
    trace_.frequency_hz = 1000000000;  // an edge's cycle is its nanosecond
    trace_edges_ = 0;
    for (size_t i = 0; i < trace_.signals.size(); ++i) {
      const PinRef& ref = trace_.signals[i].pin;
      int pin = ref.number;
      if (!ref.numbered()) {
        const auto it = port_map_.find({ref.port, ref.bit});
        if (it == port_map_.end()) {
          const std::string board = board_name_;
          Teardown();
          return "board \"" + watched_board_.name + "\": " + trace_.signals[i].name + " is on " +
                 ref.Name() + ", which the firmware's board \"" + board +
                 "\" does not map to a pin; name the pin by its number (e.g. \"GPIO26\") or "
                 "build for a board whose port map has it";
        }
        pin = it->second;
      }
      signal_of_pin_.insert({pin, static_cast<int>(i)});
      lk::Put(attach, static_cast<uint64_t>(pin), 2);
    }
  }
  if (send(fd_, attach.data(), attach.size(), MSG_NOSIGNAL) < 0) {
    Stop(Ended());
    return std::nullopt;
  }
  // The firmware runs until its first call into the core.
  AwaitYield(nullptr);
  return std::nullopt;
}

void NativeTarget::Teardown() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  if (pid_ > 0) {
    kill(pid_, SIGKILL);
    while (waitpid(pid_, nullptr, 0) < 0 && errno == EINTR) {
    }
  }
  pid_ = -1;
}

void NativeTarget::Restart() {
  Teardown();
  if (auto err = Start()) Stop(*err);
}

bool NativeTarget::Send(wire::ByteView bytes) {
  if (!stopped_.empty() || fd_ < 0) return false;
  if (StopRequested() != 0) return false;
  pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  return true;
}

TimeNs NativeTarget::SentBy() const {
  return std::max(line_free_ns_, now_ns_) + static_cast<TimeNs>(pending_.size()) * frame_ns_;
}

bool NativeTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  const size_t had = out.size();
  for (;;) {
    if (!stopped_.empty() || fd_ < 0 || StopRequested() != 0) return false;
    const TimeNs until = std::min(deadline_ns, now_ns_ + kSliceNs);
    tx_packet_.assign(1, static_cast<uint8_t>(lk::Type::kRun));
    lk::Put(tx_packet_, static_cast<uint64_t>(until), 8);
    tx_packet_.push_back(1);  // stop at output
    tx_packet_.insert(tx_packet_.end(), pending_.begin(), pending_.end());
    pending_.clear();
    if (send(fd_, tx_packet_.data(), tx_packet_.size(), MSG_NOSIGNAL) < 0) {
      Stop(Ended());
      return false;
    }
    if (!AwaitYield(&out)) return false;
    if (out.size() > had || now_ns_ >= deadline_ns) return true;
  }
}

bool NativeTarget::ReadPacket(size_t& size) {
  if (rx_packet_.size() < lk::kMaxPacketBytes + 64) rx_packet_.resize(lk::kMaxPacketBytes + 64);
  for (;;) {
    pollfd p{fd_, POLLIN, 0};
    const int ready = poll(&p, 1, spec_.stall_wall_seconds * 1000);
    if (ready < 0 && errno == EINTR) {
      if (StopRequested() != 0) return false;
      continue;
    }
    if (ready == 0) {
      Stop("the firmware answered no grant of time for " +
           std::to_string(spec_.stall_wall_seconds) + " s of wall time at " +
           std::to_string(static_cast<double>(now_ns_) / 1e9) +
           " s: a loop that calls nothing of the core (no clock read, pin, serial or wait) "
           "never lets simulated time move");
      return false;
    }
    const ssize_t n = recv(fd_, rx_packet_.data(), rx_packet_.size(), 0);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    size = static_cast<size_t>(n);
    return true;
  }
}

bool NativeTarget::AwaitYield(wire::Bytes* out) {
  for (;;) {
    size_t size = 0;
    if (!ReadPacket(size)) {
      if (stopped_.empty() && StopRequested() == 0) Stop(Ended());
      return false;
    }
    if (size == 0) continue;
    const uint8_t type = rx_packet_[0];
    lk::Reader r(rx_packet_.data() + 1, size - 1);
    switch (static_cast<lk::Type>(type)) {
      case lk::Type::kOutput:
        while (r.left() >= lk::kOutputRecord) {
          r.GetI64();
          const auto value = static_cast<uint8_t>(r.Get(1));
          if (out != nullptr) out->push_back(value);
        }
        break;
      case lk::Type::kEdges:
        AddEdges(r);
        break;
      case lk::Type::kNote: {
        std::string note(r.Rest());
        if (std::find(notes_.begin(), notes_.end(), note) == notes_.end()) notes_.push_back(note);
        break;
      }
      case lk::Type::kStopped: {
        const auto fault = static_cast<lk::Fault>(r.Get(1));
        if (fault == lk::Fault::kDivisionByZero) stop_kind_ = FirmwareFaultKind::kDivisionByZero;
        Stop(std::string(r.Rest()) + " at " + std::to_string(static_cast<double>(now_ns_) / 1e9) +
             " s");
        return false;
      }
      case lk::Type::kYield:
        now_ns_ = r.GetI64();
        line_free_ns_ = r.GetI64();
        frame_ns_ = r.GetI64();
        dropped_ += r.Get(4);
        return true;
      default:
        Stop("the firmware sent a packet of unknown type " + std::to_string(type));
        return false;
    }
  }
}

void NativeTarget::AddEdges(lk::Reader& r) {
  while (r.left() >= lk::kEdgeRecord) {
    const TimeNs t = r.GetI64();
    const int pin = static_cast<int>(r.Get(2));
    const bool level = r.Get(1) != 0;
    const auto [first, last] = signal_of_pin_.equal_range(pin);
    for (auto it = first; it != last; ++it) {
      if (trace_edges_ >= kMaxPinEdges) {
        trace_.complete_until_ns = std::min(trace_.complete_until_ns, t - 1);
        continue;
      }
      auto& edges = trace_.signals[static_cast<size_t>(it->second)].edges;
      edges.push_back(PinEdge{t, static_cast<uint64_t>(t), level});
      ++trace_edges_;
    }
  }
}

void NativeTarget::Stop(std::string what) {
  if (stopped_.empty()) stopped_ = std::move(what);
  Teardown();
}

std::string NativeTarget::Ended() {
  const std::string at = " at " + std::to_string(static_cast<double>(now_ns_) / 1e9) + " s";
  if (pid_ <= 0) return "the firmware process is gone" + at;
  if (fd_ >= 0) {
    close(fd_);
    fd_ = -1;
  }
  int status = 0;
  pid_t r = 0;
  // The link closed: the process is ending. One that lives on is ended here.
  for (int i = 0; i < 200 && (r = waitpid(pid_, &status, WNOHANG)) == 0; ++i) usleep(5000);
  if (r == 0) {
    kill(pid_, SIGKILL);
    while (waitpid(pid_, nullptr, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return "the firmware closed its link to the runner" + at;
  }
  pid_ = -1;
  if (r < 0) return "the firmware process is gone" + at;
  if (WIFSIGNALED(status)) {
    return "the firmware process was killed by signal " + std::to_string(WTERMSIG(status)) + " (" +
           strsignal(WTERMSIG(status)) + ")" + at;
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) {
    return "the firmware could not be started (exec failed)";
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 2) {
    return "the program exited with status 2: it is not firmware built for the native target";
  }
  return "the firmware process exited with status " +
         std::to_string(WIFEXITED(status) ? WEXITSTATUS(status) : -1) + at;
}

std::optional<std::string> NativeTarget::FirmwareStopped() const {
  if (stopped_.empty()) return std::nullopt;
  return stopped_;
}

std::optional<FirmwareFault> NativeTarget::FirmwareFaulted() const {
  if (stopped_.empty()) return std::nullopt;
  FirmwareFault f;
  f.kind = stop_kind_;
  f.what = stopped_;
  return f;
}

std::optional<std::string> NativeTarget::WatchPins(const Board& board) {
  watching_ = true;
  watched_board_ = board;
  trace_ = PinTrace::For(board);
  return std::nullopt;
}

std::vector<std::string> NativeTarget::Caveats() const {
  std::vector<std::string> c = {
      "the native target runs the sketch's own code in no simulated time: only its calls into "
      "the core (clock reads, pins, serial, waits) take time, at the figures of the board \"" +
      board_name_ + "\""};
  for (const std::string& n : notes_) c.push_back("the sketch used " + n);
  if (dropped_ > 0) {
    c.push_back(std::to_string(dropped_) +
                " byte(s) from the host were dropped by the sketch's full receive buffer");
  }
  return c;
}

}  // namespace moco::conformance
