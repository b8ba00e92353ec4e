// Writes fixtures/sessions/dfmoco-uno-workflow.jsonl (docs/sessions.md): a
// typical Dragonframe-style exchange with the emulated DFMoco sketch on an Uno
// (dfmoco-protocol.txt "Messages", FACTS.md "DFMoco"), in virtual time.
// Usage: dfmoco_session_gen <source dir> [output path]
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "devices/dfmoco_arduino/dfmoco_arduino.h"
#include "session/session.h"
#include "wire/dfmoco.h"

namespace {

using moco::sim::kNsPerMs;
using moco::sim::TimeNs;

// The host's side of the session: when each line is sent.
std::vector<std::pair<TimeNs, std::string>> HostScript() {
  std::vector<std::pair<TimeNs, std::string>> s;
  auto at = [&](int64_t ms, std::string line) { s.emplace_back(ms * kNsPerMs, line + "\r\n"); };
  at(500, "hi");
  at(600, "pr 1 4000");
  at(610, "pr 2 25000");
  at(700, "mp 1");
  at(710, "mp 2");
  at(1000, "mm 1 3000");
  at(1010, "mm 2 -1500");
  for (int64_t t = 1250; t <= 3750; t += 250) at(t, "ms");
  at(4000, "mp 1");
  at(4200, "mm 1 0");
  at(5000, "sm 1");
  for (int64_t t = 5250; t <= 6500; t += 250) at(t, "ms");
  at(7000, "zm 2");
  at(7200, "xx 1");
  at(7300, "mm 7 5");
  at(8000, "ms");
  return s;
}

class Recorder final : public moco::devices::ByteSink {
 public:
  explicit Recorder(const moco::sim::Scheduler& s) : s_(s) {}
  void Write(moco::wire::ByteView bytes) override {
    moco::session::SessionEntry e;
    e.t_ns = s_.Now();
    e.from = moco::session::Origin::kDevice;
    e.bytes.assign(bytes.begin(), bytes.end());
    entries.push_back(std::move(e));
  }
  std::vector<moco::session::SessionEntry> entries;

 private:
  const moco::sim::Scheduler& s_;
};

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s <source dir> [output path]\n", argv[0]);
    return 2;
  }
  try {
    const std::filesystem::path src = argv[1];
    const std::filesystem::path out_path =
        argc > 2 ? std::filesystem::path(argv[2])
                 : src / "fixtures/sessions/dfmoco-uno-workflow.jsonl";
    const moco::devices::DfmocoProfile profile =
        moco::devices::LoadDfmocoProfile(src / "fixtures/profiles/dfmoco-uno.json");

    moco::sim::Scheduler sched;
    Recorder rec(sched);
    moco::devices::DfmocoArduino dev(sched, rec, profile);
    std::vector<moco::session::SessionEntry> entries;
    dev.PowerOn();
    for (const auto& [t, line] : HostScript()) {
      sched.RunUntil(t);
      moco::session::SessionEntry e;
      e.t_ns = t;
      e.from = moco::session::Origin::kHost;
      e.bytes.assign(line.begin(), line.end());
      // Device output written before this instant goes first.
      for (auto& d : rec.entries) entries.push_back(std::move(d));
      rec.entries.clear();
      entries.push_back(std::move(e));
      dev.OnHostBytes(moco::wire::ByteView(entries.back().bytes));
    }
    sched.RunUntil(9000 * kNsPerMs);
    for (auto& d : rec.entries) entries.push_back(std::move(d));

    moco::session::SessionHeader header;
    header.protocol = moco::wire::Protocol::kDfmoco;
    header.device = "dfmoco-uno";
    header.clock = "virtual";
    header.note =
        "DFMoco 2.0.0 on an Uno (fixtures/profiles/dfmoco-uno.json), powered on at t = 0: hi, "
        "pr (one clamped to 20000), mm on two motors with ms polling and the periodic mp "
        "reports, a stop while moving, zm, an unknown command and an invalid motor";
    std::ofstream out(out_path, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot create " + out_path.string());
    auto write = [&](const nlohmann::json& j) {
      out << j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) << '\n';
    };
    write(moco::session::HeaderToJson(header));
    const moco::dfmoco::Dialect dialect = profile.Dialect();
    for (moco::session::SessionEntry& e : entries) {
      const std::string text(e.bytes.begin(), e.bytes.end());
      std::string_view line(text);
      line.remove_suffix(2);  // every chunk here is one "\r\n" line
      if (e.from == moco::session::Origin::kHost) {
        const auto cmd = moco::dfmoco::ParseHostLine(line, dialect);
        e.decoded.push_back(cmd.ok() ? moco::dfmoco::Describe(*cmd) : "parse error");
      } else {
        const auto reply = moco::dfmoco::ParseDeviceLine(line, dialect);
        e.decoded.push_back(reply.ok() ? moco::dfmoco::Describe(*reply, dialect) : "?");
      }
      nlohmann::json j = moco::session::EntryToJson(e);
      j["text"] = text;
      write(j);
    }
    if (!out.flush()) throw std::runtime_error("write error on " + out_path.string());
    std::printf("wrote %zu entries to %s\n", entries.size(), out_path.string().c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dfmoco_session_gen: %s\n", e.what());
    return 1;
  }
  return 0;
}
