// Targets of the conformance runner (ARCHITECTURE "conformance"): in-process
// on the virtual clock, PTY/serial and TCP on the steady clock.
#include "conformance/targets/target.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <exception>

#include "base/termios_speed.h"
#include "devices/registry.h"
#include "sim/io.h"
#include "sim/rig.h"
#include "wire/protocol.h"

#include "conformance/targets/native_target.h"

#ifdef MOCO_HAVE_SIMAVR
#include "conformance/targets/simavr_target.h"
#endif

namespace moco::conformance {
namespace {

std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "RequestStop runs in a signal handler");

int64_t SteadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

void RequestStop(int signal_number) { g_stop_signal.store(signal_number); }
int StopRequested() { return g_stop_signal.load(); }

// --- InProcessTarget ----------------------------------------------------------------

InProcessTarget::InProcessTarget(std::string name, DeviceFactory factory)
    : name_(std::move(name)), factory_(std::move(factory)) {}

InProcessTarget::~InProcessTarget() {
  device_.reset();  // before the scheduler it schedules on
}

std::unique_ptr<InProcessTarget> InProcessTarget::ForModel(const std::string& model,
                                                           const std::string& profile_path,
                                                           std::optional<wire::Protocol> speaking) {
  const devices::DeviceModel* m = devices::FindDeviceModel(model);
  // NVM outlives the device, so Restart() is a power cycle that keeps it.
  auto nvm =
      m != nullptr && m->keeps_state ? std::make_shared<devices::MemoryStateStore>() : nullptr;
  const devices::DeviceStart start{speaking};
  // The profile is read once, at the first Open(); every Restart() builds the
  // device from what was read then (a file edited during a run changes
  // nothing in it).
  auto maker = std::make_shared<devices::DeviceMaker>();
  return std::make_unique<InProcessTarget>(
      model, [model, profile_path, nvm, start, maker](sim::Scheduler& s, devices::ByteSink& sink) {
        if (!*maker) *maker = devices::PrepareDevice(model, profile_path, start);
        return (*maker)(s, sink, nvm.get(), start);
      });
}

void InProcessTarget::Build() {
  device_.reset();
  scheduler_ = std::make_unique<sim::Scheduler>();
  sink_.pending.clear();
  device_ = factory_(*scheduler_, sink_);
  device_->PowerOn();
  device_->OnHostLink(true);
}

std::optional<std::string> InProcessTarget::Open() {
  try {
    Build();
  } catch (const std::exception& e) {
    device_.reset();
    return "cannot build the in-process device \"" + name_ + "\": " + e.what();
  }
  return std::nullopt;
}

void InProcessTarget::Restart() { Build(); }

bool InProcessTarget::Send(wire::ByteView bytes) {
  if (!device_) return false;
  device_->OnHostBytes(bytes);
  return true;
}

bool InProcessTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  if (!device_) return false;
  while (sink_.pending.empty()) {
    const std::optional<TimeNs> next = scheduler_->NextEventTime();
    if (!next || *next > deadline_ns) {
      if (deadline_ns > scheduler_->Now()) scheduler_->RunUntil(deadline_ns);
      break;
    }
    scheduler_->RunNext();
  }
  out.insert(out.end(), sink_.pending.begin(), sink_.pending.end());
  sink_.pending.clear();
  return true;
}

bool InProcessTarget::SetEStop(bool engaged) {
  sim::Rig* rig = device_ ? device_->rig() : nullptr;
  if (rig == nullptr) return false;
  if (engaged) {
    rig->EngageEStop();
  } else {
    rig->ReleaseEStop();
  }
  return true;
}

bool InProcessTarget::SetLimitInput(int set, bool high, bool active) {
  sim::Rig* rig = device_ ? device_->rig() : nullptr;
  if (rig == nullptr || set < 1 || set > rig->limit_set_count()) return false;
  rig->ForceInput(set, high ? sim::SwitchInput::kHigh : sim::SwitchInput::kLow, active);
  return true;
}

bool InProcessTarget::SetGioInput(int bit, bool level) {
  sim::GioPort* gio = device_ ? device_->gio() : nullptr;
  if (gio == nullptr || bit < 0 || bit > 31) return false;
  gio->SetRawInput(bit, level);
  return true;
}

bool InProcessTarget::CanPressButton(std::string_view button) const {
  return device_ != nullptr && device_->HasButton(button);
}

bool InProcessTarget::PressButton(std::string_view button) {
  if (!CanPressButton(button)) return false;
  device_->PressButton(button);
  return true;
}

DeviceOutputs InProcessTarget::Outputs() const {
  if (!device_) return {};
  outputs_.dmx = device_->dmx_out();
  outputs_.gio = device_->gio();
  outputs_.camera = device_->camera_out();
  return DeviceOutputs::Through(outputs_, outputs_.dmx != nullptr, outputs_.gio != nullptr,
                                outputs_.camera != nullptr);
}

// --- FdTarget ------------------------------------------------------------------------

FdTarget::FdTarget(Kind kind, std::string address, uint32_t baud, std::string scheme)
    : kind_(kind), address_(std::move(address)), baud_(baud), scheme_(std::move(scheme)) {}

FdTarget::~FdTarget() {
  if (fd_ >= 0) close(fd_);
}

std::string FdTarget::Name() const {
  if (kind_ == Kind::kTcp) return "tcp:" + address_;
  return scheme_ + ":" + address_ + " @" + std::to_string(baud_);
}

bool FdTarget::Lose(std::string why) {
  if (!lost_) lost_ = std::move(why);
  return false;
}

std::string FdTarget::NotADevice(const struct stat& st) const {
  const char* what = S_ISREG(st.st_mode)    ? "a regular file"
                     : S_ISDIR(st.st_mode)  ? "a directory"
                     : S_ISFIFO(st.st_mode) ? "a FIFO"
                     : S_ISBLK(st.st_mode)  ? "a block device"
                                            : "not a terminal";
  return scheme_ + ":" + address_ + " is " + what +
         ", not a serial port, PTY or socket; nothing was written to it. Give the device's "
         "port (e.g. /dev/ttyUSB0) or the PTY path mocosim printed";
}

std::optional<std::string> FdTarget::Open() {
  if (kind_ == Kind::kSerial) {
    const std::optional<speed_t> speed = base::TermiosSpeed(baud_);
    if (!speed) {
      return base::NonStandardBaudHint(baud_, "the protocols' lines: " + wire::DefaultBaudList());
    }
    // Never O_CREAT or O_TRUNC, and nothing is written before the path is
    // known to be a terminal, a character device or a socket: a regular file
    // given by mistake is left as it was.
    struct stat st {};
    if (stat(address_.c_str(), &st) == 0 && !S_ISCHR(st.st_mode) && !S_ISSOCK(st.st_mode)) {
      return NotADevice(st);
    }
    fd_ = open(address_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
    if (fd_ < 0) {
      return "cannot open " + address_ + ": " + std::strerror(errno) +
             "; check the path (is the device or mocosim running?) and its permissions";
    }
    if (fstat(fd_, &st) != 0 ||
        !(isatty(fd_) != 0 || S_ISCHR(st.st_mode) || S_ISSOCK(st.st_mode))) {
      close(fd_);
      fd_ = -1;
      return NotADevice(st);
    }
    // Two hosts on one port steal each other's answers, and each would judge
    // the device by the half it saw: a second mococheck (or any program that
    // locks the port the same way) is refused instead.
    if (flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      const int err = errno;
      close(fd_);
      fd_ = -1;
      if (err == EWOULDBLOCK) {
        return scheme_ + ":" + address_ +
               " is in use by another program that holds it locked (another mococheck?); two "
               "hosts on one port steal each other's answers: wait for it to end, or give each "
               "run its own device";
      }
      return "cannot lock " + address_ + ": " + std::strerror(err);
    }
    termios t{};
    if (tcgetattr(fd_, &t) == 0) {
      cfmakeraw(&t);
      cfsetispeed(&t, *speed);
      cfsetospeed(&t, *speed);
      t.c_cflag |= CLOCAL | CREAD;
      tcsetattr(fd_, TCSANOW, &t);
    }
  } else {
    const size_t colon = address_.rfind(':');
    const std::string host = address_.substr(0, colon);
    const std::string port = address_.substr(colon + 1);
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    addrinfo* res = nullptr;
    if (getaddrinfo(host.c_str(), port.c_str(), &hints, &res) != 0 || res == nullptr) {
      return "cannot resolve " + address_ + "; give tcp:HOST:PORT, e.g. tcp:127.0.0.1:5000";
    }
    int err = 0;
    for (addrinfo* a = res; a != nullptr; a = a->ai_next) {
      fd_ = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
      if (fd_ < 0) continue;
      if (connect(fd_, a->ai_addr, a->ai_addrlen) == 0) break;
      err = errno;
      close(fd_);
      fd_ = -1;
    }
    freeaddrinfo(res);
    if (fd_ < 0) {
      return "cannot connect to " + address_ + ": " + std::strerror(err) +
             "; is the device (or mocosim --tcp) listening there?";
    }
    const int one = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    fcntl(fd_, F_SETFL, fcntl(fd_, F_GETFL) | O_NONBLOCK);
  }
  origin_ns_ = SteadyNs();
  return std::nullopt;
}

void FdTarget::Restart() {
  wire::Bytes drop;
  Receive(Now(), drop);
}

TimeNs FdTarget::Now() const { return SteadyNs() - origin_ns_; }

bool FdTarget::Send(wire::ByteView bytes) {
  if (fd_ < 0 || lost_) return false;
  size_t done = 0;
  while (done < bytes.size()) {
    if (StopRequested() != 0) return false;
    // MSG_NOSIGNAL: a peer that closed is an EPIPE here, never a SIGPIPE.
    const ssize_t w = kind_ == Kind::kTcp
                          ? send(fd_, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL)
                          : write(fd_, bytes.data() + done, bytes.size() - done);
    if (w > 0) {
      hung_up_since_ns_.reset();
      done += static_cast<size_t>(w);
      continue;
    }
    if (w < 0 && (errno == EAGAIN || errno == EINTR)) {
      pollfd p{fd_, POLLOUT, 0};
      poll(&p, 1, 100);
      continue;
    }
    // EIO on a PTY whose other side is closed for now: the device may reopen it.
    if (w < 0 && errno == EIO && kind_ == Kind::kSerial) {
      HungUp();
      return false;
    }
    return Lose(std::string("writing to the device failed: ") +
                (w < 0 ? std::strerror(errno) : "nothing written"));
  }
  return true;
}

bool FdTarget::Receive(TimeNs deadline_ns, wire::Bytes& out) {
  if (fd_ < 0 || lost_) return false;
  for (;;) {
    if (StopRequested() != 0) return false;
    uint8_t buf[4096];
    const ssize_t r = read(fd_, buf, sizeof buf);
    if (r > 0) {
      hung_up_since_ns_.reset();
      out.insert(out.end(), buf, buf + r);
      return true;
    }
    // A reset (a device killed with bytes still unread) is a close too.
    if (r == 0 || (r < 0 && errno == ECONNRESET)) return Lose("the device closed the connection");
    // EIO: a PTY whose other side is closed for now (the device may reopen it).
    const bool hung_up = errno == EIO;
    if (hung_up && !HungUp()) return false;
    if (!hung_up) hung_up_since_ns_.reset();
    if (errno != EAGAIN && errno != EINTR && !hung_up) {
      return Lose(std::string("reading from the device failed: ") + std::strerror(errno));
    }
    const TimeNs left_ns = deadline_ns - Now();
    if (left_ns <= 0) return true;
    const int wait_ms = static_cast<int>((left_ns + sim::kNsPerMs - 1) / sim::kNsPerMs);
    if (hung_up) {
      poll(nullptr, 0, std::min(wait_ms, 10));
    } else {
      pollfd p{fd_, POLLIN, 0};
      poll(&p, 1, wait_ms);
    }
  }
}

bool FdTarget::HungUp() {
  const TimeNs now = Now();
  if (!hung_up_since_ns_) hung_up_since_ns_ = now;
  if (now - *hung_up_since_ns_ < kHangUpGraceNs) return true;
  return Lose("the far end of " + address_ + " has been closed for " +
              std::to_string(kHangUpGraceNs / sim::kNsPerSecond) +
              " s (the emulator serving it stopped, or the adapter was unplugged)");
}

// --- parsing -------------------------------------------------------------------------

std::variant<TargetSpec, std::string> ParseTargetSpec(std::string_view text) {
  const size_t colon = text.find(':');
  const std::string_view scheme = colon == std::string_view::npos ? text : text.substr(0, colon);
  const std::string rest =
      colon == std::string_view::npos ? std::string() : std::string(text.substr(colon + 1));
  const std::string usage =
      "; give in-process:MODEL (e.g. in-process:dmc16), pty:PATH, tcp:HOST:PORT, "
      "simavr:PATH.elf[@MCU[:HZ]] or native:PATH[@PORT]";
  if (rest.empty()) return "--target \"" + std::string(text) + "\" names no address" + usage;
  if (scheme == "in-process") return TargetSpec{TargetSpec::Kind::kInProcess, rest, "in-process"};
  if (scheme == "simavr") {
    const auto parsed = ParseSimavrAddress(rest);
    if (const auto* err = std::get_if<std::string>(&parsed)) {
      return "--target \"" + std::string(text) + "\": " + *err;
    }
    return TargetSpec{TargetSpec::Kind::kSimavr, rest, "simavr"};
  }
  if (scheme == "native") {
    const auto parsed = ParseNativeAddress(rest);
    if (const auto* err = std::get_if<std::string>(&parsed)) {
      return "--target \"" + std::string(text) + "\": " + *err;
    }
    return TargetSpec{TargetSpec::Kind::kNative, rest, "native"};
  }
  if (scheme == "pty" || scheme == "serial") {
    return TargetSpec{TargetSpec::Kind::kSerial, rest, std::string(scheme)};
  }
  if (scheme == "tcp") {
    const size_t c = rest.rfind(':');
    if (c == std::string::npos || c == 0 || c + 1 == rest.size()) {
      return "--target \"" + std::string(text) + "\" lacks a host or a port" + usage;
    }
    for (size_t i = c + 1; i < rest.size(); ++i) {
      if (rest[i] < '0' || rest[i] > '9') {
        return "--target \"" + std::string(text) + "\": the port is not a number" + usage;
      }
    }
    return TargetSpec{TargetSpec::Kind::kTcp, rest, "tcp"};
  }
  return "--target \"" + std::string(text) + "\": unknown kind \"" + std::string(scheme) + "\"" +
         usage;
}

std::variant<SimavrSpec, std::string> ParseSimavrAddress(std::string_view address) {
  const std::string usage =
      "; give simavr:PATH.elf, optionally @MCU or @MCU:HZ, e.g. "
      "simavr:dfmoco.elf@atmega328p:16000000";
  SimavrSpec spec;
  const size_t at = address.rfind('@');
  spec.elf_path = std::string(address.substr(0, at));
  if (spec.elf_path.empty()) return "no firmware ELF path" + usage;
  if (at == std::string_view::npos) return spec;
  const std::string_view mcu_hz = address.substr(at + 1);
  const size_t colon = mcu_hz.find(':');
  spec.mcu = std::string(mcu_hz.substr(0, colon));
  if (spec.mcu.empty()) return "the MCU after '@' is empty" + usage;
  if (colon == std::string_view::npos) return spec;
  const std::string_view hz = mcu_hz.substr(colon + 1);
  const bool digits =
      !hz.empty() && hz.size() <= 10 &&
      std::all_of(hz.begin(), hz.end(), [](char c) { return c >= '0' && c <= '9'; });
  uint64_t value = 0;
  for (const char c : digits ? hz : std::string_view())
    value = value * 10 + static_cast<uint64_t>(c - '0');
  if (value == 0 || value > 0xFFFFFFFFu) {
    return "the clock \"" + std::string(hz) + "\" is not a number of hertz in 1..4294967295" +
           usage;
  }
  spec.frequency_hz = static_cast<uint32_t>(value);
  return spec;
}

std::variant<std::unique_ptr<Target>, std::string> MakeTarget(const TargetSpec& spec,
                                                              const std::string& profile_path,
                                                              uint32_t baud) {
  switch (spec.kind) {
    case TargetSpec::Kind::kInProcess: {
      const devices::DeviceModel* model = devices::FindDeviceModel(spec.address);
      if (model == nullptr) {
        std::string known;
        for (const auto& m : devices::DeviceModels())
          known += (known.empty() ? "" : ", ") + std::string(m.name);
        return "unknown in-process model \"" + spec.address + "\"; the models are: " + known;
      }
      return std::unique_ptr<Target>(InProcessTarget::ForModel(spec.address, profile_path));
    }
    case TargetSpec::Kind::kSerial:
      return std::unique_ptr<Target>(std::make_unique<FdTarget>(
          FdTarget::Kind::kSerial, spec.address, baud, spec.scheme.empty() ? "pty" : spec.scheme));
    case TargetSpec::Kind::kTcp:
      return std::unique_ptr<Target>(
          std::make_unique<FdTarget>(FdTarget::Kind::kTcp, spec.address, baud));
    case TargetSpec::Kind::kNative: {
      auto parsed = ParseNativeAddress(spec.address);
      if (auto* err = std::get_if<std::string>(&parsed)) return std::move(*err);
      // The firmware sets its own baud rate; --baud does not apply.
      return std::unique_ptr<Target>(
          std::make_unique<NativeTarget>(std::move(std::get<NativeSpec>(parsed))));
    }
    case TargetSpec::Kind::kSimavr: {
      auto parsed = ParseSimavrAddress(spec.address);
      if (auto* err = std::get_if<std::string>(&parsed)) return std::move(*err);
#ifdef MOCO_HAVE_SIMAVR
      // The firmware sets its own baud rate; --baud does not apply.
      return std::unique_ptr<Target>(
          std::make_unique<SimavrTarget>(std::move(std::get<SimavrSpec>(parsed))));
#else
      return std::string(
          "this mococheck was built without simavr, so it cannot run firmware; install "
          "libsimavr-dev (ci/setup-deps) and configure and build again");
#endif
    }
  }
  return std::string("unknown target kind");
}

}  // namespace moco::conformance
