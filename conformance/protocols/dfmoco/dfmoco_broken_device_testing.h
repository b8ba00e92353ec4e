// Test support: a DFMoco Arduino broken on purpose at the wire. The real
// emulated sketch with a filter on its output (each line it writes handed to
// a LineBreakage, dfmoco-protocol.txt "Message Format") and, optionally, on
// its input (the host's bytes changed before the sketch reads them), run
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
// stage).
class BrokenDfmoco final : public devices::Device, private devices::ByteSink {
 public:
  BrokenDfmoco(sim::Scheduler& s, devices::ByteSink& out, LineBreakage b,
               devices::DfmocoProfile profile, InputBreakage in = {})
      : s_(s),
        out_(out),
        b_(std::move(b)),
        in_(std::move(in)),
        inner_(s, *this, std::move(profile)) {}
  std::string_view Model() const override { return "dfmoco-broken"; }
  devices::LineSettings Line() const override { return inner_.Line(); }
  void PowerOn() override { inner_.PowerOn(); }
  void PowerOff() override {
    inner_.PowerOff();
    partial_.clear();
  }
  bool Powered() const override { return inner_.Powered(); }
  void OnHostBytes(wire::ByteView bytes) override {
    if (!in_) {
      Track(bytes);
      inner_.OnHostBytes(bytes);
      return;
    }
    // Whole lines go through the input breakage; the terminators pass as sent.
    std::string pass;
    for (const uint8_t b : bytes) {
      const char c = static_cast<char>(b);
      if (c != '\r' && c != '\n') {
        reading_.push_back(c);
        continue;
      }
      if (!reading_.empty()) pass += in_(reading_);
      reading_.clear();
      pass.push_back(c);
    }
    const wire::ByteView changed(reinterpret_cast<const uint8_t*>(pass.data()), pass.size());
    Track(changed);
    inner_.OnHostBytes(changed);
  }
  void OnHostLink(bool open) override { inner_.OnHostLink(open); }
  sim::Rig* rig() override { return inner_.rig(); }
  sim::GioPort* gio() override { return inner_.gio(); }

 private:
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
  std::string partial_;       // the sketch's line being written
  std::string reading_;       // the host's line before the input breakage
  std::string command_;       // the host's line being read
  std::string last_command_;  // the host's last whole line
  devices::DfmocoArduino inner_;
};

inline RunReport RunBroken(LineBreakage b, RunOptions options = {},
                           devices::DfmocoProfile profile = {}, InputBreakage in = {}) {
  InProcessTarget target("dfmoco-broken",
                         [b, profile, in](sim::Scheduler& s, devices::ByteSink& out) {
                           return std::make_unique<BrokenDfmoco>(s, out, b, profile, in);
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

using proof::ExpectCaught;
using proof::FailedMusts;

}  // namespace moco::conformance::dfmoco_testing

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DFMOCO_DFMOCO_BROKEN_DEVICE_TESTING_H_
