// `mococheck certify`, `keygen` and `verify` (docs/certificates.md): a
// sealed certificate of a full run, the key pair that seals it, and the
// check anyone can make of it, with the recorded traffic judged again.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <iostream>
#include <memory>

#include "base/file_io.h"
#include "cli_numbers.h"
#include "conformance/cli/run_setup.h"
#include "conformance/core/certificate.h"
#include "conformance/core/report.h"
#include "conformance/core/seal.h"
#include "conformance/targets/native_target.h"
#include "conformance/targets/recorded_target.h"
#include "wire/protocol.h"

namespace moco::conformance::cli {
namespace {

using nlohmann::json;

// The largest certificate `verify` reads (a full DMC run's is a few MB).
constexpr size_t kMaxCertificateBytes = size_t{512} << 20;
// The largest firmware image `certify` digests.
constexpr size_t kMaxFirmwareBytes = size_t{64} << 20;
constexpr size_t kMaxKeyBytes = size_t{64} << 10;

std::string Basename(const std::string& path) {
  const size_t slash = path.rfind('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// Reads a key, a profile or an image: a message naming `option` and the file
// when it cannot.
std::optional<std::string> ReadInput(const std::string& option, const std::string& path,
                                     size_t max_bytes, std::string& text) {
  if (auto err = base::ReadFileBounded(path, &text, {.max_bytes = max_bytes})) {
    return option + " " + path + ": " + *err;
  }
  return std::nullopt;
}

// Now as "2026-12-05T21:37:51Z".
std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

// --- certify -------------------------------------------------------------------------------

struct CertifyArgs {
  RunArgs run;
  std::string key_path, out_path;
};

// The firmware a simavr: or native: target runs: its file name, size and digest.
std::optional<std::string> FirmwareOf(const PreparedRun& p, json& firmware) {
  firmware = nullptr;
  std::string path;
  if (p.resolved.spec.kind == TargetSpec::Kind::kSimavr) {
    auto spec = ParseSimavrAddress(p.resolved.spec.address);
    if (const auto* err = std::get_if<std::string>(&spec)) return *err;
    path = std::get<SimavrSpec>(spec).elf_path;
  } else if (p.resolved.spec.kind == TargetSpec::Kind::kNative) {
    auto spec = ParseNativeAddress(p.resolved.spec.address);
    if (const auto* err = std::get_if<std::string>(&spec)) return *err;
    path = std::get<NativeSpec>(spec).path;
  } else {
    return std::nullopt;
  }
  std::string image;
  if (auto err = ReadInput("--target", path, kMaxFirmwareBytes, image)) return *err;
  firmware = {{"file", Basename(path)},
              {"target", p.resolved.spec.address},
              {"bytes", image.size()},
              {"sha256", Sha256Hex(image)}};
  return std::nullopt;
}

// A file the run read, kept whole so that the run can be made again: its
// name, digest and text.
std::optional<std::string> Embed(const std::string& option, const std::string& path, json& out) {
  out = nullptr;
  if (path.empty()) return std::nullopt;
  std::string text;
  if (auto err = ReadInput(option, path, base::kMaxInputFileBytes, text)) return *err;
  out = {{"file", Basename(path)}, {"sha256", Sha256Hex(text)}, {"text", text}};
  return std::nullopt;
}

bool IsBuiltInDriver(const std::string& name) {
  for (const DriverProfile& d : BuiltInDrivers()) {
    if (d.name == name) return true;
  }
  return false;
}

// The options of the run, with the files it read, enough to run it again.
std::optional<std::string> RunSection(const RunArgs& a, Protocol proto, json& run) {
  run = {{"target", a.target_text},
         {"protocol", std::string(ProtocolName(proto))},
         {"dialect", a.dialect},
         {"seed", a.seed},
         {"steps", a.steps},
         {"baud", a.baud},
         {"deadline_ms", a.deadline_ms},
         {"deadlines", a.deadlines},
         {"answer_timeout_ms", a.answer_timeout_ms},
         {"wait_every_answer", a.wait_every_answer},
         {"position_gap_ms", a.position_gap_ms}};
  json profile, board, driver;
  if (auto err = Embed("--profile", a.profile, profile)) return err;
  if (auto err = Embed("--board", a.board_path, board)) return err;
  if (!a.board_path.empty()) {
    const std::string name = a.driver.empty() ? "a4988" : a.driver;
    if (IsBuiltInDriver(name)) {
      driver = {{"name", name}};
    } else if (auto err = Embed("--driver", name, driver)) {
      return err;
    }
  }
  run["profile"] = profile;
  run["board"] = board;
  run["driver"] = driver;
  return std::nullopt;
}

int Certify(const CertifyArgs& c) {
  const RunArgs& a = c.run;
  std::string key;
  if (auto err = ReadInput("--key", c.key_path, kMaxKeyBytes, key)) return Fail(*err);
  std::string key_error;
  if (!PublicKeyOf(key, &key_error)) return Fail("--key " + c.key_path + ": " + key_error);
  int exit_code = kExitUsage;
  std::optional<PreparedRun> p =
      PrepareRun(a, exit_code, {{"--out", c.out_path}}, {{"--key", c.key_path}});
  if (!p) return exit_code;
  CertificateParts parts;
  if (auto err = FirmwareOf(*p, parts.firmware)) return Fail(*err);
  if (auto err = RunSection(a, p->resolved.protocol, parts.run)) return Fail(*err);
  // From here a signal stops the run; a run cut short gets no certificate.
  InstallStopHandlers();
  RecordingTarget recorder(std::move(p->resolved.target));
  const std::optional<RunReport> report = ExecuteRun(a, *p, recorder);
  if (!report) return kExitUsage;
  // Every report is written now; the --html page is written again, headed by
  // the certificate, once it is sealed (a run that gets none keeps its page).
  int reports_exit = WriteReports(a, *report);
  if (const std::string why = report->NoVerdictReason(); !why.empty()) {
    return Fail("no certificate written: the run has no verdict (" + why +
                "); a certificate needs a complete run");
  }
  json firmware_after;
  if (auto err = FirmwareOf(*p, firmware_after); err || firmware_after != parts.firmware) {
    return Fail(
        "no certificate written: the firmware image changed during the run; certify "
        "again");
  }
  // The files embedded before the run must still be the ones the run read.
  json run_after;
  if (auto err = RunSection(a, p->resolved.protocol, run_after)) {
    return Fail("no certificate written: a file the run read cannot be read again (" + *err +
                "); certify again");
  }
  for (const char* file : {"profile", "board", "driver"}) {
    if (run_after[file] != parts.run[file]) {
      return Fail(std::string("no certificate written: the --") + file +
                  " file changed during the run; certify again");
    }
  }
  parts.device = {{"target", report->target},
                  {"protocol", report->protocol},
                  {"introduced", report->device},
                  {"info", report->device.empty() ? json(nullptr) : report->device_info}};
  parts.report = JsonReport(*report);
  parts.call_log = recorder.log();
  parts.made_at = UtcNow();
  json cert = MakeCertificate(parts);
  if (auto err = SealCertificate(cert, key)) return Fail("could not seal: " + *err);
  const std::string text = cert.dump(1, ' ', false, json::error_handler_t::replace) + "\n";
  if (auto err = base::WriteFileAtomically(c.out_path, text)) {
    return Fail("could not write the certificate: " + *err);
  }
  std::cout << "certificate: " << c.out_path << " (" << base::FormatByteSize(text.size())
            << ", sealed by key " << cert["seal"]["key_id"].get<std::string>() << ")" << std::endl;
  if (!a.html_path.empty()) {
    const std::string page = CertificateHtmlPage(*report, cert, Basename(c.out_path), false);
    if (auto err = base::WriteFileAtomically(a.html_path, page)) {
      std::cerr << "mococheck: could not write --html " << a.html_path << ": " << *err
                << "; the certificate is written" << std::endl;
      reports_exit = kExitUsage;
    }
  }
  return reports_exit;
}

// --- keygen --------------------------------------------------------------------------------

// Writes `text` as a new file `path` with `mode`: created under a temporary
// name (O_EXCL, O_NOFOLLOW) and linked to `path` only when complete, so a
// key is never overwritten, never half written, and never written through a
// planted symlink.
std::optional<std::string> WriteNewFile(const std::string& path, const std::string& text,
                                        mode_t mode) {
  static int written = 0;
  const std::string tmp =
      path + ".partial-" + std::to_string(getpid()) + "-" + std::to_string(++written);
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, mode);
  if (fd < 0) return path + ": cannot create it (" + std::strerror(errno) + ")";
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t w = write(fd, text.data() + done, text.size() - done);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) break;
    done += static_cast<size_t>(w);
  }
  const bool ok = done == text.size() && fchmod(fd, mode) == 0 && fsync(fd) == 0;
  const int saved = errno;
  close(fd);
  if (!ok) {
    unlink(tmp.c_str());
    return path + ": could not write it (" + std::strerror(saved) + ")";
  }
  const int linked = link(tmp.c_str(), path.c_str());
  const int link_errno = errno;
  unlink(tmp.c_str());
  if (linked != 0) {
    if (link_errno == EEXIST) {
      return path + " exists: keygen never overwrites a key; remove it or choose another --out";
    }
    return path + ": could not create it (" + std::strerror(link_errno) + ")";
  }
  return std::nullopt;
}

int Keygen(const std::string& out) {
  const std::string pub = out + ".pub";
  for (const std::string& p : {out, pub}) {
    struct stat st {};
    if (lstat(p.c_str(), &st) == 0) {
      return Fail(p + " exists: keygen never overwrites a key; remove it or choose another --out");
    }
  }
  std::string error;
  const auto keys = GenerateKeyPair(&error);
  if (!keys) return Fail(error);
  if (auto err = WriteNewFile(out, keys->private_pem, 0600)) return Fail(*err);
  if (auto err = WriteNewFile(pub, keys->public_pem, 0644)) {
    unlink(out.c_str());
    return Fail(*err);
  }
  const auto raw = RawPublicKey(keys->public_pem, &error);
  std::cout << "private key: " << out << " (keep it secret; certify --key " << out << ")\n"
            << "public key:  " << pub << " (publish it; verify --key " << pub << ")\n"
            << "key id:      " << (raw ? KeyId(*raw) : "?") << std::endl;
  return 0;
}

// --- verify --------------------------------------------------------------------------------

struct VerifyArgs {
  std::string cert_path, key_path, firmware_path, badge_path, html_path, target, profile;
  bool replay = false, summary = false;
};

// The RunArgs and run preparation the certificate's "run" section gives,
// with `target` (the playback) in place of its device.
std::optional<std::string> PrepareReplay(const json& run, PreparedRun& p, RunArgs& a) {
  const auto proto = wire::ParseProtocol(run.value("protocol", ""));
  if (!proto) return "its run names no protocol this mococheck knows";
  p.resolved.protocol = *proto;
  p.runner = FindRunner(*proto);
  if (p.runner == nullptr) return "this mococheck has no suites for its protocol";
  try {
    a.dialect = run.value("dialect", "auto");
    a.seed = run.value("seed", uint64_t{1});
    a.steps = run.value("steps", 40);
    a.deadline_ms = run.value("deadline_ms", int64_t{250});
    a.deadlines = run.value("deadlines", std::vector<std::string>{});
    a.answer_timeout_ms = run.value("answer_timeout_ms", int64_t{2000});
    a.wait_every_answer = run.value("wait_every_answer", false);
    a.position_gap_ms = run.value("position_gap_ms", int64_t{200});
  } catch (const json::exception& e) {
    return std::string("its run options do not parse: ") + e.what();
  }
  if (auto err = CheckDialect(a.dialect, *p.runner)) return err;
  if (auto err = SetHostOptions(a, p.options)) return err;
  const json board = run.value("board", json());
  if (board.is_object()) {
    auto b = ParseBoard(board.value("text", ""), board.value("file", "board"));
    if (const auto* err = std::get_if<std::string>(&b)) return *err;
    const json driver = run.value("driver", json());
    auto d = driver.contains("text")
                 ? ParseDriver(driver.value("text", ""), driver.value("file", "driver"))
                 : LoadDriver(driver.value("name", "a4988"));
    if (const auto* err = std::get_if<std::string>(&d)) return *err;
    p.board = std::get<Board>(b);
    PinJudgeOptions pins;
    pins.board = *p.board;
    pins.driver = std::get<DriverProfile>(d);
    p.options.pins = pins;
  }
  return std::nullopt;
}

// Plays the certificate's traffic to its suite again; the differences (empty
// when the verdicts are the same), or a message why it could not.
std::vector<std::string> Replay(const json& cert, std::string& summary,
                                std::optional<RunReport>& replayed) {
  std::string error;
  auto log = CallLogOf(cert, &error);
  if (!log) return {"the transcript: " + error};
  auto playback = PlaybackTarget::FromLog(std::move(*log), &error);
  if (!playback) return {"the transcript: " + error};
  PreparedRun p;
  RunArgs a;
  a.quiet = true;
  if (auto err = PrepareReplay(cert.value("run", json::object()), p, a)) {
    return {"the run cannot be made again: " + *err};
  }
  replayed = ExecuteRun(a, p, *playback, false);
  const std::optional<RunReport>& report = replayed;
  if (!report) return {"the replay did not start"};
  if (!playback->divergence().empty()) {
    return {"this mococheck plays other traffic than the certified run (" + playback->divergence() +
            "): its suites differ from the certifying mococheck's, so the verdicts cannot be "
            "judged again here"};
  }
  std::vector<std::string> diffs =
      CompareVerdicts(cert.value("report", json::object()), JsonReport(*report));
  if (!playback->Exhausted()) {
    diffs.push_back("the replay ended with calls of the transcript unplayed (" +
                    std::to_string(playback->calls_played()) + " played)");
  }
  const auto counts = report->RuleCounts();
  auto count = [&](Status st) {
    const auto it = counts.find(st);
    return it == counts.end() ? size_t{0} : it->second;
  };
  summary = std::to_string(playback->calls_played()) + " recorded calls played; " +
            std::to_string(count(Status::kPass) + count(Status::kFail) + count(Status::kNoted)) +
            " rules judged again";
  return diffs;
}

// Runs the certificate's suite, with its options, against the device
// `v.target` and compares each rule's and case's verdict with the sealed
// ones (their evidence differs from run to run on a real clock). The
// differences, or why the run has no verdict; `target_error` set (and the
// message printed) when the target could not be made or opened.
std::vector<std::string> RunAgainst(const json& cert, const VerifyArgs& v, std::string& summary,
                                    bool& target_error) {
  PreparedRun p;
  RunArgs a;
  a.quiet = true;
  const json run = cert.value("run", json::object());
  if (auto err = PrepareReplay(run, p, a)) return {"the run cannot be made again: " + *err};
  TargetRequest request;
  request.text = v.target;
  request.profile = v.profile;
  request.baud = run.value("baud", uint32_t{0});
  request.protocol = p.resolved.protocol;
  auto resolved = ResolveTarget(request);
  if (const auto* err = std::get_if<std::string>(&resolved)) {
    target_error = true;
    Fail(*err);
    return {};
  }
  p.resolved = std::move(std::get<ResolvedTarget>(resolved));
  InstallStopHandlers();
  Target& target = *p.resolved.target;
  const std::optional<RunReport> report = ExecuteRun(a, p, target, false);
  if (!report) {
    target_error = true;  // ExecuteRun printed why
    return {};
  }
  if (const std::string why = report->NoVerdictReason(); !why.empty()) {
    return {"the run against " + target.Name() + " has no verdict (" + why + ")"};
  }
  summary = "the suite run again against " + target.Name();
  return CompareVerdicts(cert.value("report", json::object()), JsonReport(*report), false);
}

int VerifyCertificate(const VerifyArgs& v, const json& cert, const std::string& key);

int Verify(const VerifyArgs& v) {
  if (!v.html_path.empty() && !v.replay) {
    return Fail(
        "--html needs --replay: the page is rendered from the certificate's transcript, "
        "judged again");
  }
  // Each output checked before anything is read: writable, neither input,
  // not the other output.
  const std::pair<std::string, std::string> outputs[] = {{"--html", v.html_path},
                                                         {"--badge", v.badge_path}};
  for (const auto& [option, path] : outputs) {
    if (path.empty()) continue;
    if (auto err = base::CheckOutputPath(path, option)) return Fail(*err);
    if (base::SameFile(path, v.cert_path) || base::SameFile(path, v.key_path)) {
      return Fail(option + " " + path + " is the certificate or the key; choose another path");
    }
  }
  if (!v.html_path.empty() && !v.badge_path.empty() && base::SameFile(v.html_path, v.badge_path)) {
    return Fail("--html and --badge are the same file; give each its own");
  }
  std::string text, key;
  if (auto err = ReadInput("certificate", v.cert_path, kMaxCertificateBytes, text)) {
    return Fail(*err);
  }
  if (auto err = ReadInput("--key", v.key_path, kMaxKeyBytes, key)) return Fail(*err);
  std::string key_error;
  if (!RawPublicKey(key, &key_error)) return Fail("--key " + v.key_path + ": " + key_error);
  json cert;
  try {
    cert = json::parse(text);
  } catch (const json::parse_error& e) {
    return Fail("certificate " + v.cert_path + " is not JSON (" + e.what() +
                "); give a file 'mococheck certify' wrote");
  }
  try {
    return VerifyCertificate(v, cert, key);
  } catch (const json::exception& e) {
    // A certificate whose seal holds but whose fields have the wrong types.
    std::cout << "problem:     the certificate is malformed: " << e.what() << "\n"
              << "result: NOT VERIFIED" << std::endl;
    return 1;
  }
}

int VerifyCertificate(const VerifyArgs& v, const json& cert, const std::string& key) {
  CertificateCheck check = CheckCertificate(cert, key);
  if (!v.firmware_path.empty()) {
    std::string image;
    if (auto err = ReadInput("--firmware", v.firmware_path, kMaxFirmwareBytes, image)) {
      return Fail(*err);
    }
    const json fw = cert.value("firmware", json());
    if (!fw.is_object()) {
      check.problems.push_back(
          "--firmware: the certificate names no firmware image (its target "
          "ran none)");
    } else if (fw.value("sha256", "") != Sha256Hex(image)) {
      check.problems.push_back("--firmware " + v.firmware_path + " is not the certified image (" +
                               fw.value("file", "?") + ", SHA-256 " + fw.value("sha256", "?") +
                               ")");
    }
  }
  if (!cert.is_object() || cert.value("format", "") != kCertificateFormat) {
    for (const std::string& p : check.problems) std::cout << "problem:     " << p << "\n";
    std::cout << "result: NOT VERIFIED" << std::endl;
    return 1;
  }
  // What the certificate says of itself, read without trusting its types
  // (the seal is checked above; a wrong type is only shown as "?").
  auto part = [&](const char* field) {
    const auto it = cert.find(field);
    return it != cert.end() && it->is_object() ? *it : json::object();
  };
  auto text = [](const json& j, const char* field) {
    const auto it = j.find(field);
    return it != j.end() && it->is_string() ? it->get<std::string>() : std::string("?");
  };
  const json device = part("device"), fw = part("firmware"), report = part("report");
  const std::string introduced = text(device, "introduced");
  std::cout << "certificate: " << v.cert_path << "\n"
            << "device:      "
            << (introduced.empty() || introduced == "?" ? text(device, "target") : introduced)
            << " (" << text(device, "protocol") << ")\n";
  if (!fw.empty()) {
    std::cout << "firmware:    " << text(fw, "file") << " sha256 " << text(fw, "sha256") << "\n";
  }
  const auto exit_it = report.find("exit_code");
  const int sealed_exit =
      exit_it != report.end() && exit_it->is_number_integer() ? exit_it->get<int>() : 2;
  std::cout << "verdict:     " << (sealed_exit == 0 ? "PASS" : "FAIL") << " (exit code "
            << sealed_exit << ")\n";
  std::optional<RunReport> replayed;
  if (v.replay && check.problems.empty()) {
    std::string summary;
    const std::vector<std::string> diffs = Replay(cert, summary, replayed);
    for (const std::string& d : diffs) check.problems.push_back("replay: " + d);
    if (diffs.empty()) std::cout << "replay:      same verdicts (" << summary << ")\n";
  } else if (v.replay) {
    std::cout << "replay:      not made (the certificate does not verify)\n";
  }
  if (!v.target.empty() && check.problems.empty()) {
    std::string summary;
    bool target_error = false;
    const std::vector<std::string> diffs = RunAgainst(cert, v, summary, target_error);
    if (target_error) return kExitUsage;
    for (const std::string& d : diffs) check.problems.push_back("device: " + d);
    if (diffs.empty()) std::cout << "device:      same verdicts (" << summary << ")\n";
  }
  if (!check.problems.empty()) {
    for (const std::string& p : check.problems) std::cout << "problem:     " << p << "\n";
    std::cout << "result: NOT VERIFIED" << std::endl;
    return 1;
  }
  std::cout << "seal:        Ed25519, key " << check.key_id << ", intact\n";
  if (v.summary) std::cout << "\n" << CertificateSummary(cert, Basename(v.cert_path)) << "\n";
  if (!v.badge_path.empty()) {
    if (auto err = base::WriteFileAtomically(v.badge_path, CertificateBadge(cert))) {
      return Fail("--badge: " + *err);
    }
    std::cout << "badge:       " << v.badge_path << "\n";
  }
  if (!v.html_path.empty() && replayed) {
    const std::string page = CertificateHtmlPage(*replayed, cert, Basename(v.cert_path), true);
    if (auto err = base::WriteFileAtomically(v.html_path, page)) return Fail("--html: " + *err);
    std::cout << "html:        " << v.html_path << "\n";
  }
  std::cout << "result: VERIFIED" << std::endl;
  return 0;
}

}  // namespace

Runner AddCertifyCommand(CLI::App& app, CLI::App*& sub) {
  auto c = std::make_shared<CertifyArgs>();
  sub = app.add_subcommand(
      "certify",
      "Run the whole suite against a device and write a sealed certificate of it: the device's "
      "identity, the firmware's SHA-256 (simavr:, native:), every verdict with its evidence and "
      "the whole "
      "recorded exchange (docs/certificates.md)");
  AddRunOptions(sub, c->run, false);
  sub->add_option("--key", c->key_path, "Ed25519 private key to seal with ('mococheck keygen')")
      ->required();
  sub->add_option("--out", c->out_path, "Write the certificate (JSON) here")
      ->required()
      ->check(moco::cli::NonEmptyPath());
  return [c] { return Certify(*c); };
}

Runner AddKeygenCommand(CLI::App& app, CLI::App*& sub) {
  auto out = std::make_shared<std::string>();
  sub = app.add_subcommand("keygen",
                           "Make an Ed25519 key pair for sealing certificates: KEY (private, mode "
                           "0600) and KEY.pub (to publish); never overwrites a file");
  sub->add_option("--out", *out, "The private key's path; the public key goes to PATH.pub")
      ->required()
      ->check(moco::cli::NonEmptyPath());
  return [out] { return Keygen(*out); };
}

Runner AddVerifyCommand(CLI::App& app, CLI::App*& sub) {
  auto v = std::make_shared<VerifyArgs>();
  sub = app.add_subcommand(
      "verify",
      "Check a certificate: its seal against the maker's public key, each part against the "
      "sealed digests (naming what changed), its rule catalogue against this mococheck's; with "
      "--replay also judge its recorded traffic again. Exit 0 verified, 1 not, 2 usage");
  sub->add_option("certificate", v->cert_path, "The certificate (JSON)")->required();
  sub->add_option("--key", v->key_path, "The maker's Ed25519 public key (PEM, KEY.pub)")
      ->required();
  sub->add_option("--firmware", v->firmware_path,
                  "Also check that this image is the certified firmware");
  sub->add_option("--badge", v->badge_path,
                  "Once verified, write a badge (SVG) of the result here, for a README")
      ->check(moco::cli::NonEmptyPath());
  sub->add_option("--html", v->html_path,
                  "With --replay, once verified: write the report page (self-contained HTML) of "
                  "the replayed run here, headed by the certificate's facts")
      ->check(moco::cli::NonEmptyPath());
  sub->add_flag("--summary", v->summary,
                "Once verified, print a paragraph (Markdown) of the result for a README");
  sub->add_option("--target", v->target,
                  "Also run the certificate's suite, with its options, against this device "
                  "(as `run --target`) and compare every rule's and case's verdict");
  sub->add_option("--profile", v->profile, "Device profile (JSON) for an in-process --target")
      ->check(CLI::ExistingFile);
  sub->add_flag("--replay", v->replay,
                "Judge the recorded traffic again with this mococheck's rules, without a device, "
                "and compare every verdict");
  return [v] { return Verify(*v); };
}

}  // namespace moco::conformance::cli
