// Certificates (docs/certificates.md): the sealing primitives against their
// published test vectors and laws, the call log's record/playback law (a run
// played back from its log reaches the same verdicts, a broken device's
// failures included), and every kind of tampering named by CheckCertificate.
#include "conformance/core/certificate.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include "conformance/core/report.h"
#include "conformance/core/seal.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/protocols/dmc/dmc_broken_device.h"
#include "conformance/protocols/dmc/dmc_protocol.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "conformance/targets/recorded_target.h"
#include "devices/dfmoco_arduino/dfmoco_arduino.h"

namespace moco::conformance {
namespace {

using nlohmann::json;

// --- primitives ----------------------------------------------------------------------------

TEST(Seal, Sha256MatchesTheFips180Vectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(Seal, Base64MatchesRfc4648AndRefusesNonCanonicalText) {
  EXPECT_EQ(Base64(""), "");
  EXPECT_EQ(Base64("f"), "Zg==");
  EXPECT_EQ(Base64("fo"), "Zm8=");
  EXPECT_EQ(Base64("foo"), "Zm9v");
  EXPECT_EQ(Base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(FromBase64("Zm9vYg=="), "foob");
  for (const char* bad : {"Zm9", "Zm9v!", "Zh==", "Z===", "Zm=v", "=Zm9"}) {
    EXPECT_FALSE(FromBase64(bad)) << bad;
  }
}

RC_GTEST_PROP(SealProp, Base64AndDeflateRoundTrip, (const std::string& bytes)) {
  RC_ASSERT(FromBase64(Base64(bytes)) == bytes);
  std::string error;
  RC_ASSERT(Inflate(Deflate(bytes), bytes.size(), &error) == bytes);
}

TEST(Seal, InflateRefusesAWrongLengthOrDamage) {
  const std::string text(10000, 'x');
  const std::string packed = Deflate(text);
  std::string error;
  EXPECT_FALSE(Inflate(packed, text.size() - 1, &error));
  EXPECT_FALSE(Inflate(packed, text.size() + 1, &error));
  std::string damaged = packed;
  damaged[damaged.size() / 2] ^= 0x55;
  EXPECT_FALSE(Inflate(damaged, text.size(), &error));
  EXPECT_FALSE(Inflate(packed.substr(0, packed.size() - 3), text.size(), &error));
}

TEST(Seal, SignaturesVerifyOnlyForTheirMessageAndKey) {
  std::string error;
  const auto a = GenerateKeyPair(&error);
  const auto b = GenerateKeyPair(&error);
  ASSERT_TRUE(a && b) << error;
  const auto sig = Sign(a->private_pem, "message", &error);
  ASSERT_TRUE(sig) << error;
  EXPECT_EQ(sig->size(), 64u);
  const auto raw_a = RawPublicKey(a->public_pem, &error);
  const auto raw_b = RawPublicKey(b->public_pem, &error);
  ASSERT_TRUE(raw_a && raw_b);
  EXPECT_TRUE(VerifySignature(*raw_a, "message", *sig));
  EXPECT_FALSE(VerifySignature(*raw_a, "messagE", *sig));
  EXPECT_FALSE(VerifySignature(*raw_b, "message", *sig));
  std::string flipped = *sig;
  flipped[10] ^= 1;
  EXPECT_FALSE(VerifySignature(*raw_a, "message", flipped));
  EXPECT_EQ(PublicKeyOf(a->private_pem, &error), a->public_pem);
  EXPECT_FALSE(PublicKeyOf(a->public_pem, &error));
  EXPECT_FALSE(RawPublicKey(a->private_pem, &error));
  EXPECT_FALSE(RawPublicKey("", &error));
}

// --- record and play back ------------------------------------------------------------------

// A DFMoco device from the emulator with `faults`, on a virtual clock.
std::unique_ptr<Target> Dfmoco(devices::DfmocoFaults faults = {}) {
  return std::make_unique<InProcessTarget>(
      "dfmoco", [faults](sim::Scheduler& s, devices::ByteSink& out) {
        return std::make_unique<devices::DfmocoArduino>(s, out, devices::DfmocoProfile{}, faults);
      });
}

struct Recorded {
  RunReport report;
  std::string log;
};

template <typename RunFn>
Recorded Record(std::unique_ptr<Target> target, const RunOptions& options, RunFn run) {
  RecordingTarget rec(std::move(target));
  EXPECT_EQ(rec.Open(), std::nullopt);
  Recorded r{run(rec, options), {}};
  if (const auto lost = rec.LinkLost()) r.report.target_error = *lost;
  r.report.target_caveats = rec.Caveats();
  r.log = rec.log();
  return r;
}

template <typename RunFn>
RunReport PlayBack(const std::string& log, const RunOptions& options, RunFn run,
                   std::string* divergence = nullptr) {
  std::string error;
  auto playback = PlaybackTarget::FromLog(log, &error);
  EXPECT_TRUE(playback) << error;
  EXPECT_EQ(playback->Open(), std::nullopt);
  RunReport report = run(*playback, options);
  if (const auto lost = playback->LinkLost()) report.target_error = *lost;
  report.target_caveats = playback->Caveats();
  if (divergence != nullptr) *divergence = playback->divergence();
  EXPECT_TRUE(!playback->divergence().empty() || playback->Exhausted());
  return report;
}

TEST(CallLog, ABrokenDevicesRunPlaysBackToTheSameFailures) {
  devices::DfmocoFaults faults;
  faults.ms_width_delta = 1;  // `ms` one digit too wide: DFM-MS-002
  RunOptions options;
  const Recorded rec = Record(Dfmoco(faults), options, RunDfmoco);
  ASSERT_EQ(ExitCode(rec.report), 1);
  ASSERT_EQ(rec.report.rules.at("DFM-MS-002").status, Status::kFail);
  std::string divergence;
  const RunReport again = PlayBack(rec.log, options, RunDfmoco, &divergence);
  EXPECT_EQ(divergence, "");
  EXPECT_EQ(CompareVerdicts(JsonReport(rec.report), JsonReport(again)), std::vector<std::string>{});
  EXPECT_EQ(again.rules.at("DFM-MS-002").status, Status::kFail);

  // The log holds the traffic both ways: the sketch's greeting at power-on,
  // then the host's `hi` and its answer.
  std::string error;
  const auto traffic = TrafficOfCallLog(rec.log, &error);
  ASSERT_GE(traffic.size(), 3u) << error;
  EXPECT_FALSE(traffic[0].from_host);
  EXPECT_EQ(traffic[0].bytes.substr(0, 3), "hi ");
  const auto host = std::find_if(traffic.begin(), traffic.end(),
                                 [](const LoggedChunk& c) { return c.from_host; });
  ASSERT_NE(host, traffic.end());
  EXPECT_EQ(host->bytes, "hi\r\n");
  const auto sum = SummarizeCallLog(rec.log, &error);
  ASSERT_TRUE(sum);
  EXPECT_EQ(sum->target, "in-process:dfmoco");
  EXPECT_TRUE(sum->virtual_clock);
  EXPECT_GT(sum->device_bytes, 0u);
}

TEST(CallLog, AnotherSeedDivergesAndSaysWhere) {
  RunOptions options;
  options.cases = "random/*";
  options.random.seed = 1;
  const Recorded rec = Record(Dfmoco(), options, RunDfmoco);
  options.random.seed = 2;
  std::string divergence;
  const RunReport again = PlayBack(rec.log, options, RunDfmoco, &divergence);
  // Where the other sequence first asks something else, the playback stops
  // and says so; the run ends with the link lost.
  EXPECT_EQ(divergence.rfind("call ", 0), 0u) << divergence;
  EXPECT_NE(divergence.find("where the recorded run"), std::string::npos) << divergence;
  EXPECT_NE(again.target_error.find(divergence), std::string::npos) << again.target_error;
}

// The runs of an in-process DMC-16 that read its outputs (DMX levels, I/O
// outputs, camera lines): every read is in the log, so the rules judged on
// them are judged again from it, a broken camera stage's failure included.
TEST(CallLog, AnInProcessDevicesOutputsAreJudgedAgainFromTheLog) {
  RunOptions options;
  options.cases = "rt/*";
  const std::vector<std::string> output_rules = {"DMC-DMX-009", "DMC-DMX-010", "DMC-RT-019",
                                                 "DMC-RT-020",  "DMC-RT-022",  "DMC-RT-023",
                                                 "DMC-RT-025"};
  const Recorded rec = Record(InProcessTarget::ForModel("dmc16", ""), options, RunDmc);
  std::string divergence;
  const RunReport again = PlayBack(rec.log, options, RunDmc, &divergence);
  EXPECT_EQ(divergence, "");
  EXPECT_EQ(CompareVerdicts(JsonReport(rec.report), JsonReport(again)), std::vector<std::string>{});
  for (const std::string& id : output_rules) {
    EXPECT_EQ(rec.report.rules.at(id).status, Status::kPass) << id;
    EXPECT_EQ(again.rules.at(id).status, Status::kPass) << id;
  }

  // A DMC-16 that reads a stills run's shutter angles as 180..270 degrees
  // exposes each frame at the wrong time: DMC-RT-023 fails, and again from
  // the log.
  const dmc_testing::InputBreakage late_shutter = [](wire::ByteView bytes) {
    wire::Bytes out(bytes.begin(), bytes.end());
    const auto f = dmc::DecodeFrame(bytes);
    if (!f.ok()) return out;
    const auto m = dmc::DecodeHostMessage(f.value());
    if (!m.ok()) return out;
    const auto* run = std::get_if<dmc::RtRunMove>(&m.value());
    if (run == nullptr || !run->camera_open_angle_deg) return out;
    dmc::RtRunMove late = *run;
    late.camera_open_angle_deg = 180;
    return dmc::Encode(f.value().id, dmc::HostMessage{late});
  };
  auto broken = std::make_unique<InProcessTarget>(
      "dmc16-broken", [late_shutter](sim::Scheduler& s, devices::ByteSink& out) {
        return std::make_unique<dmc_testing::BrokenDmc16>(s, out, dmc_testing::PassThrough, "",
                                                          late_shutter);
      });
  const Recorded bad = Record(std::move(broken), options, RunDmc);
  ASSERT_EQ(bad.report.rules.at("DMC-RT-023").status, Status::kFail);
  const RunReport bad_again = PlayBack(bad.log, options, RunDmc, &divergence);
  EXPECT_EQ(divergence, "");
  EXPECT_EQ(bad_again.rules.at("DMC-RT-023").status, Status::kFail);
  EXPECT_EQ(CompareVerdicts(JsonReport(bad.report), JsonReport(bad_again)),
            std::vector<std::string>{});
}

// A target whose name changes once it is open (as a simavr: target names its
// MCU): the playback gives each name where the recorded run read it.
TEST(CallLog, TheTargetsNameIsPlayedBackAsItChanged) {
  class Renamed final : public Target {
   public:
    std::string Name() const override { return open_ ? "renamed @ 16 MHz" : "renamed"; }
    bool VirtualClock() const override { return true; }
    bool CanRestart() const override { return false; }
    std::optional<std::string> Open() override {
      open_ = true;
      return std::nullopt;
    }
    void Restart() override {}
    TimeNs Now() const override { return 0; }
    bool Send(wire::ByteView) override { return true; }
    bool Receive(TimeNs, wire::Bytes&) override { return false; }

   private:
    bool open_ = false;
  };
  RecordingTarget rec(std::make_unique<Renamed>());
  EXPECT_EQ(rec.Name(), "renamed");
  ASSERT_EQ(rec.Open(), std::nullopt);
  EXPECT_EQ(rec.Name(), "renamed @ 16 MHz");
  rec.Now();
  std::string error;
  auto playback = PlaybackTarget::FromLog(rec.log(), &error);
  ASSERT_TRUE(playback) << error;
  EXPECT_EQ(playback->Name(), "renamed");
  EXPECT_EQ(playback->Open(), std::nullopt);
  EXPECT_EQ(playback->Name(), "renamed @ 16 MHz");
  playback->Now();
  EXPECT_TRUE(playback->Exhausted());
  EXPECT_EQ(playback->divergence(), "");
  const auto sum = SummarizeCallLog(rec.log(), &error);
  ASSERT_TRUE(sum) << error;
  EXPECT_EQ(sum->target, "renamed @ 16 MHz");
  EXPECT_EQ(sum->calls, 2u);
}

// The profile an in-process device is built from is read once, at Open():
// a power cycle builds the same device even when the file has changed (or
// is no profile any more) meanwhile, so what a run read is what a
// certificate embeds (certify also checks the file after the run).
TEST(InProcessTarget, ReadsItsProfileOnceForEveryPowerCycle) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("profile-once-" + std::to_string(getpid()));
  std::ofstream(path) << R"({"device": "dfmoco", "board": "mega", "firmware": "2.0.0"})";
  auto target = InProcessTarget::ForModel("dfmoco", path.string());
  ASSERT_EQ(target->Open(), std::nullopt);
  auto greeting = [&] {
    wire::Bytes got;
    target->Receive(target->Now() + 2 * sim::kNsPerSecond, got);
    return std::string(got.begin(), got.end());
  };
  const std::string first = greeting();
  EXPECT_NE(first.find("hi 2 8 "), std::string::npos) << first;  // a Mega's 8 motors
  std::ofstream(path) << "{ this is no profile";
  target->Restart();
  EXPECT_EQ(greeting(), first);
  std::filesystem::remove(path);
}

TEST(CallLog, AStackshotRunWithRestartsPlaysBack) {
  RunOptions options;
  const Recorded rec = Record(InProcessTarget::ForModel("stackshot3x", ""), options, RunStackshot);
  std::string error;
  const auto sum = SummarizeCallLog(rec.log, &error);
  ASSERT_TRUE(sum) << error;
  EXPECT_GT(sum->restarts, 0u);
  std::string divergence;
  const RunReport again = PlayBack(rec.log, options, RunStackshot, &divergence);
  EXPECT_EQ(divergence, "");
  EXPECT_EQ(CompareVerdicts(JsonReport(rec.report), JsonReport(again)), std::vector<std::string>{});
}

TEST(CallLog, ACutOrDamagedLogIsRefusedWithoutACrash) {
  RunOptions options;
  options.cases = "connect/*";
  const Recorded rec = Record(Dfmoco(), options, RunDfmoco);
  std::string error;
  EXPECT_FALSE(PlaybackTarget::FromLog("MOCOLOG", &error));
  EXPECT_FALSE(SummarizeCallLog("garbage", &error));
  for (size_t cut = 8; cut < rec.log.size(); cut += rec.log.size() / 37 + 1) {
    const std::string part = rec.log.substr(0, cut);
    SummarizeCallLog(part, &error);  // either whole entries or "cut short", never a crash
    auto playback = PlaybackTarget::FromLog(part, &error);
    if (!playback) continue;
    playback->Open();
    const RunReport r = RunDfmoco(*playback, options);
    EXPECT_FALSE(playback->divergence().empty()) << cut;
  }
}

RC_GTEST_PROP(CallLogProp, AnyBytesAfterTheHeaderAreReadWithoutACrash, (const std::string& tail)) {
  // Either format's magic (this one's, and mococheck 0.1.0's), a 3-byte
  // name, a virtual clock that can restart, then anything.
  const std::string magic = *rc::gen::element<std::string>("MOCOLOG2", "MOCOLOG1");
  const std::string log = magic +
                          std::string(
                              "\x03"
                              "abc"
                              "\x01\x01",
                              6) +
                          tail;
  std::string error;
  SummarizeCallLog(log, &error);
  TrafficOfCallLog(log, &error);
  auto playback = PlaybackTarget::FromLog(log, &error);
  RC_ASSERT(playback != nullptr);
  playback->Open();
  RunOptions options;
  options.cases = "connect/hi";
  const RunReport r = RunDfmoco(*playback, options);
  // No run of a case is made of random bytes: the playback says where it
  // stopped, and the run lost its link there.
  RC_ASSERT(!playback->divergence().empty());
  RC_ASSERT(!r.NoVerdictReason().empty() || playback->LinkLost().has_value());
}

TEST(CompareVerdicts, AnotherRunOfADeviceIsComparedByVerdictsNotEvidence) {
  RunOptions options;
  options.cases = "connect/*,motor/*";
  const json a = JsonReport(Record(Dfmoco(), options, RunDfmoco).report);
  json b = a;
  for (json& c : b["cases"]) {
    for (json& r : c["rules"]) {
      for (json& e : r["evidence"]) e["t_ns"] = e.value("t_ns", int64_t{0}) + 1000;
    }
    c["target_ms"] = 1.0;
  }
  EXPECT_FALSE(CompareVerdicts(a, b).empty());  // a replay must match to the nanosecond
  EXPECT_EQ(CompareVerdicts(a, b, false), std::vector<std::string>{});
  b["rules"][0]["status"] = "fail";
  const auto diffs = CompareVerdicts(a, b, false);
  ASSERT_FALSE(diffs.empty());
  EXPECT_EQ(diffs[0].rfind("rule " + a["rules"][0].value("id", "?") + ": sealed", 0), 0u)
      << diffs[0];
}

// --- certificates --------------------------------------------------------------------------

class Certificates : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string error;
    keys_ = new KeyPair(*GenerateKeyPair(&error));
    other_ = new KeyPair(*GenerateKeyPair(&error));
    RunOptions options;
    options.cases = "connect/*,motor/*";
    const Recorded rec = Record(Dfmoco(), options, RunDfmoco);
    CertificateParts parts;
    parts.device = {{"target", rec.report.target}, {"introduced", rec.report.device}};
    parts.firmware = {{"file", "fw.elf"}, {"sha256", Sha256Hex("image")}, {"bytes", 5}};
    parts.run = {{"protocol", "dfmoco"}, {"seed", 1}};
    parts.report = JsonReport(rec.report);
    parts.call_log = rec.log;
    cert_ = new json(MakeCertificate(parts));
    const auto err = SealCertificate(*cert_, keys_->private_pem);
    ASSERT_EQ(err, std::nullopt);
  }
  static void TearDownTestSuite() {
    delete keys_;
    delete other_;
    delete cert_;
  }
  // The problems CheckCertificate finds in the certificate after `change`.
  template <typename Change>
  static std::vector<std::string> After(Change change) {
    json c = *cert_;
    change(c);
    return CheckCertificate(c, keys_->public_pem).problems;
  }
  static std::string Joined(const std::vector<std::string>& v) {
    std::string s;
    for (const std::string& x : v) s += x + "\n";
    return s;
  }
  static KeyPair* keys_;
  static KeyPair* other_;
  static json* cert_;
};
KeyPair* Certificates::keys_ = nullptr;
KeyPair* Certificates::other_ = nullptr;
json* Certificates::cert_ = nullptr;

TEST_F(Certificates, AnIntactCertificateVerifiesAndSurvivesAJsonRoundTrip) {
  const json reparsed = json::parse(cert_->dump(1));
  const CertificateCheck check = CheckCertificate(reparsed, keys_->public_pem);
  EXPECT_EQ(Joined(check.problems), "");
  EXPECT_EQ(check.key_id, (*cert_)["seal"]["key_id"]);
  EXPECT_EQ((*cert_)["catalogue"]["sha256"], CatalogueSha256());
  std::string error;
  EXPECT_TRUE(CallLogOf(reparsed, &error)) << error;
}

// The page names the firmware image the suite ran, or says there was none
// (an emulated device); the empty part is sealed all the same.
TEST_F(Certificates, ThePageNamesTheFirmwareOrSaysThereWasNone) {
  RunOptions options;
  options.cases = "connect/*";
  const Recorded rec = Record(Dfmoco(), options, RunDfmoco);
  const std::string with = CertificateHtmlPage(rec.report, *cert_, "c.json", false);
  EXPECT_NE(with.find("<code>fw.elf sha256 " + Sha256Hex("image") + "</code>"), std::string::npos);
  EXPECT_EQ(with.find("ran no firmware image"), std::string::npos);
  json emulated = *cert_;
  emulated["firmware"] = nullptr;
  const std::string without = CertificateHtmlPage(rec.report, emulated, "c.json", false);
  EXPECT_NE(without.find("<th>firmware</th><td><code>none: the device under test ran no firmware "
                         "image</code>"),
            std::string::npos);
  EXPECT_NE(without.find("<th>sha256 of firmware</th>"), std::string::npos);
}

TEST_F(Certificates, TextThatIsNotUtf8SealsAndVerifiesThroughTheFile) {
  // A device may introduce itself with any bytes; the file holds them as
  // U+FFFD, and the seal is over that same text.
  json c = *cert_;
  c["device"]["introduced"] = std::string("hi \xff\xfe 1", 7);
  ASSERT_EQ(SealCertificate(c, keys_->private_pem), std::nullopt);
  const json back = json::parse(c.dump(1, ' ', false, json::error_handler_t::replace));
  EXPECT_EQ(Joined(CheckCertificate(back, keys_->public_pem).problems), "");
}

TEST_F(Certificates, AChangedVerdictIsNamedByItsRule) {
  const auto problems = After([](json& c) {
    for (json& r : c["report"]["rules"]) {
      if (r["id"] == "DFM-HI-001") r["status"] = "fail";
    }
  });
  EXPECT_NE(Joined(problems).find("the verdict of rule DFM-HI-001 was changed"), std::string::npos)
      << Joined(problems);
  EXPECT_EQ(problems.size(), 1u) << Joined(problems);
}

TEST_F(Certificates, OneByteOfTheTranscriptChangedIsNamed) {
  const auto problems = After([](json& c) {
    std::string data = c["transcript"]["data"];
    data[data.size() / 2] = data[data.size() / 2] == 'A' ? 'B' : 'A';
    c["transcript"]["data"] = data;
  });
  EXPECT_NE(Joined(problems).find("the transcript (\"transcript\") was changed"), std::string::npos)
      << Joined(problems);
}

TEST_F(Certificates, TheCatalogueOrFirmwareDigestChangedIsNamed) {
  auto problems = After([](json& c) { c["catalogue"]["sha256"] = std::string(64, '0'); });
  EXPECT_NE(Joined(problems).find("the rule catalogue's digest (\"catalogue\") was changed"),
            std::string::npos)
      << Joined(problems);
  EXPECT_NE(Joined(problems).find("made with another rule catalogue"), std::string::npos);
  problems = After([](json& c) { c["firmware"]["sha256"] = Sha256Hex("other image"); });
  EXPECT_NE(Joined(problems).find("the firmware image's digest (\"firmware\") was changed"),
            std::string::npos)
      << Joined(problems);
}

TEST_F(Certificates, AnOlderCatalogueResealedBySomeoneSaysSo) {
  // A certificate from another catalogue, sealed properly (as an older
  // mococheck would have): the seal holds, the catalogue differs.
  json c = *cert_;
  c["catalogue"]["sha256"] = Sha256Hex("an older catalogue");
  c["mococheck"]["version"] = "0.0.9";
  ASSERT_EQ(SealCertificate(c, keys_->private_pem), std::nullopt);
  const CertificateCheck check = CheckCertificate(c, keys_->public_pem);
  EXPECT_TRUE(check.catalogue_differs);
  ASSERT_EQ(check.problems.size(), 1u) << Joined(check.problems);
  EXPECT_NE(check.problems[0].find("made with another rule catalogue"), std::string::npos);
  EXPECT_NE(check.problems[0].find("mococheck 0.0.9"), std::string::npos);
}

TEST_F(Certificates, AnotherKeyOrAChangedManifestBreaksTheSeal) {
  const CertificateCheck other = CheckCertificate(*cert_, other_->public_pem);
  ASSERT_EQ(other.problems.size(), 1u);
  EXPECT_NE(other.problems[0].find("not by the key given"), std::string::npos);
  auto problems = After([](json& c) { c["seal"]["manifest"]["run"] = Sha256Hex("x"); });
  EXPECT_NE(Joined(problems).find("signature does not match its manifest"), std::string::npos);
  problems = After([](json& c) { c.erase("seal"); });
  EXPECT_NE(Joined(problems).find("has no seal"), std::string::npos);
  problems = After([](json& c) { c["format"] = "something else"; });
  EXPECT_NE(Joined(problems).find("not a mococheck certificate"), std::string::npos);
}

TEST_F(Certificates, ARemovedOrAddedCaseIsNamed) {
  auto problems = After([](json& c) { c["report"]["cases"].erase(0); });
  EXPECT_NE(Joined(problems).find("was removed after sealing"), std::string::npos)
      << Joined(problems);
}

}  // namespace
}  // namespace moco::conformance
