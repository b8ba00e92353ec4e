// Test support: a DFMoco Arduino broken on purpose at the wire. The real
// emulated sketch with a filter on its output (each line it writes handed to
// a LineBreakage, dfmoco-protocol.txt "Message Format") and, optionally, on
// its input (the host's bytes changed, or read late, before the sketch reads
// them), run
// through the whole runner; proving tests plant a fault this way and show the
// rule that names it failing (conformance/core/rule_proof_testing.h).
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_BROKEN_DEVICE_TESTING_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_BROKEN_DEVICE_TESTING_H_

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <set>
#include <string>
#include <string_view>
#include <utility>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "devices/dfmoco_arduino/dfmoco_arduino.h"

namespace moco::conformance::dfmoco_testing {

// What the broken device sends instead of one line the sketch wrote: `line`
// is its text without "\r\n", `last_command` the last whole line the sketch
// read from the host (without its terminator), `out` the real link.
using LineBreakage = std::function<void(const std::string& line, const std::string& last_command,
                                        sim::Scheduler& s, devices::ByteSink& out)>;

// What the sketch reads instead of one line the host sent (`line` without its
// terminator); empty: read as sent.
using InputBreakage = std::function<std::string(const std::string& line)>;

// How long after it arrives the sketch reads one line of the host (`line` as
// the input breakage left it, without its terminator); 0: at once. A line
// read late is read with "\r\n", after whatever arrives meanwhile.
using InputDelay = std::function<sim::TimeNs(const std::string& line)>;

inline void Write(devices::ByteSink& out, std::string_view bytes) {
  out.Write(wire::ByteView(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

// Writes `text` as one whole line of the sketch's form.
inline void WriteLine(devices::ByteSink& out, std::string_view text) {
  Write(out, std::string(text) + "\r\n");
}

inline void PassThrough(const std::string& line, const std::string&, sim::Scheduler&,
                        devices::ByteSink& out) {
  WriteLine(out, line);
}

// The real DFMoco sketch with a broken output stage (and, optionally, input
// stage and input delay).
class BrokenDfmoco final : public devices::Device, private devices::ByteSink {
 public:
  BrokenDfmoco(sim::Scheduler& s, devices::ByteSink& out, LineBreakage b,
               devices::DfmocoProfile profile, InputBreakage in = {}, InputDelay late = {})
      : s_(s),
        out_(out),
        b_(std::move(b)),
        in_(std::move(in)),
        late_(std::move(late)),
        inner_(s, *this, std::move(profile)) {
    RelayLineSwitchesOf(inner_);
  }
  std::string_view Model() const override { return "dfmoco-broken"; }
  devices::DeviceLine Line() const override { return inner_.Line(); }
  void PowerOn() override { inner_.PowerOn(); }
  void PowerOff() override {
    inner_.PowerOff();
    partial_.clear();
  }
  bool Powered() const override { return inner_.Powered(); }
  void OnHostBytes(wire::ByteView bytes) override {
    if (!in_ && !late_) {
      Track(bytes);
      inner_.OnHostBytes(bytes);
      return;
    }
    // Whole lines go through the input breakage and the delay; the
    // terminators pass as sent, except those of a line read late.
    std::string pass;
    for (const uint8_t b : bytes) {
      const char c = static_cast<char>(b);
      if (c != '\r' && c != '\n') {
        reading_.push_back(c);
        held_terminator_ = false;
        continue;
      }
      if (!reading_.empty()) {
        std::string line = in_ ? in_(reading_) : reading_;
        reading_.clear();
        const sim::TimeNs delay = late_ ? late_(line) : 0;
        if (delay > 0) {
          s_.After(delay, [this, line] { Read(line + "\r\n"); });
          held_terminator_ = c == '\r';  // its "\n" is still to come
          continue;
        }
        pass += line;
      }
      const bool held = held_terminator_ && c == '\n';
      held_terminator_ = false;
      if (!held) pass.push_back(c);
    }
    if (!pass.empty()) Read(pass);
  }
  void OnHostLink(bool open) override { inner_.OnHostLink(open); }
  sim::Rig* rig() override { return inner_.rig(); }
  sim::GioPort* gio() override { return inner_.gio(); }

 private:
  // The sketch reads `bytes`.
  void Read(const std::string& bytes) {
    const wire::ByteView view(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
    Track(view);
    inner_.OnHostBytes(view);
  }

  // The host's lines as the sketch reads them.
  void Track(wire::ByteView bytes) {
    for (const uint8_t b : bytes) {
      const char c = static_cast<char>(b);
      if (c == '\r' || c == '\n') {
        if (!command_.empty()) last_command_ = command_;
        command_.clear();
      } else {
        command_.push_back(c);
      }
    }
  }

  // The sketch's output, cut into lines at "\r\n".
  void Write(wire::ByteView bytes) override {
    for (const uint8_t b : bytes) {
      partial_.push_back(static_cast<char>(b));
      if (partial_.size() >= 2 && partial_.ends_with("\r\n")) {
        partial_.resize(partial_.size() - 2);
        const std::string line = std::move(partial_);
        partial_.clear();
        b_(line, last_command_, s_, out_);
      }
    }
  }

  sim::Scheduler& s_;
  devices::ByteSink& out_;
  LineBreakage b_;
  InputBreakage in_;
  InputDelay late_;
  bool held_terminator_ = false;  // the "\n" of a line read late is still to come
  std::string partial_;           // the sketch's line being written
  std::string reading_;           // the host's line before the input breakage
  std::string command_;           // the host's line being read
  std::string last_command_;      // the host's last whole line
  devices::DfmocoArduino inner_;
};

inline RunReport RunBroken(LineBreakage b, RunOptions options = {},
                           devices::DfmocoProfile profile = {}, InputBreakage in = {},
                           InputDelay late = {}) {
  InProcessTarget target("dfmoco-broken",
                         [b, profile, in, late](sim::Scheduler& s, devices::ByteSink& out) {
                           return std::make_unique<BrokenDfmoco>(s, out, b, profile, in, late);
                         });
  EXPECT_FALSE(target.Open().has_value());
  return RunDfmoco(target, options);
}

// The words of `line` split at single spaces.
inline std::vector<std::string> Fields(std::string_view line) {
  std::vector<std::string> f;
  size_t from = 0;
  for (;;) {
    const size_t sp = line.find(' ', from);
    f.emplace_back(line.substr(from, sp == std::string_view::npos ? sp : sp - from));
    if (sp == std::string_view::npos) return f;
    from = sp + 1;
  }
}

// Run options for the cases matching `cases` (e.g. "connect/*").
inline RunOptions Only(const char* cases) {
  RunOptions o;
  o.cases = cases;
  return o;
}

// Whether `line` is the word `word` or starts with it and a space.
inline bool StartsWith(const std::string& line, std::string_view word) {
  return line.rfind(std::string(word) + " ", 0) == 0 || line == word;
}

// The sketch without a fault passes every rule of `rules` on `cases`: what a
// proof on those cases catches is its fault's doing.
inline void ExpectTheSketchPasses(const char* cases, const std::set<std::string>& rules) {
  const RunReport r = RunBroken(PassThrough, Only(cases));
  for (const std::string& rule : rules) {
    ASSERT_TRUE(r.rules.count(rule)) << rule;
    EXPECT_EQ(r.rules.at(rule).status, Status::kPass)
        << rule << " is " << StatusName(r.rules.at(rule).status) << "\n"
        << ConsoleReport(r, false);
  }
}

using proof::ExpectCaught;
using proof::FailedMusts;

}  // namespace moco::conformance::dfmoco_testing

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_BROKEN_DEVICE_TESTING_H_
