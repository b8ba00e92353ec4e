// Certificates: making, sealing and checking them (certificate.h).
#include "conformance/core/certificate.h"

#include <map>
#include <set>

#include "base/xml_escape.h"
#include "conformance/core/report.h"
#include "conformance/core/seal.h"
#include "conformance/rules/catalogue.h"

#ifndef MOCO_VERSION
#error "MOCO_VERSION must be defined (the project's version, from CMake)"
#endif

namespace moco::conformance {
namespace {

using nlohmann::json;

// The parts the manifest seals one digest each for; "report" is sealed rule
// by rule and case by case besides the rest of it.
constexpr const char* kParts[] = {"format",   "mococheck", "catalogue", "device",
                                  "firmware", "run",       "transcript"};

// The catalogue as judged: each rule without the documentation tables (why a
// rule has its level, which tests prove it), which change no verdict.
json JudgedCatalogue() {
  json rules = json::parse(RulesJson());
  for (json& r : rules) {
    r.erase("reason");
    r.erase("proofs");
  }
  return rules;
}

std::string Digest(const json& j) { return Sha256Hex(CanonicalText(j)); }

// "dmc/handshake" with its position when a name repeats: the key a case is
// sealed under.
std::vector<std::string> CaseKeys(const json& cases) {
  std::vector<std::string> keys;
  std::map<std::string, int> seen;
  for (const json& c : cases) {
    std::string key = c.value("suite", "") + "/" + c.value("name", "");
    const int n = seen[key]++;
    if (n > 0) key += "#" + std::to_string(n + 1);
    keys.push_back(std::move(key));
  }
  return keys;
}

// The manifest of `cert`: each part's digest, the report's per rule and per
// case and the rest of it.
json Manifest(const json& cert) {
  json m = json::object();
  for (const char* p : kParts) m[p] = Digest(cert.contains(p) ? cert.at(p) : json(nullptr));
  const json& report = cert.contains("report") ? cert.at("report") : json::object();
  json rules = json::object(), cases = json::object();
  if (report.contains("rules") && report.at("rules").is_array()) {
    for (const json& r : report.at("rules")) rules[r.value("id", "?")] = Digest(r);
  }
  if (report.contains("cases") && report.at("cases").is_array()) {
    const std::vector<std::string> keys = CaseKeys(report.at("cases"));
    for (size_t i = 0; i < keys.size(); ++i) cases[keys[i]] = Digest(report.at("cases")[i]);
  }
  json rest = report;
  if (rest.is_object()) {
    rest.erase("rules");
    rest.erase("cases");
  }
  m["report"] = {{"rules", rules}, {"cases", cases}, {"rest", Digest(rest)}};
  return m;
}

const char* PartName(const std::string& part) {
  if (part == "format") return "the format line";
  if (part == "mococheck") return "the mococheck version";
  if (part == "catalogue") return "the rule catalogue's digest";
  if (part == "device") return "the device's identity";
  if (part == "firmware") return "the firmware image's digest";
  if (part == "run") return "the run's options";
  if (part == "transcript") return "the transcript";
  return "a part";
}

// Each difference between the sealed manifest and the one `cert` gives now.
void CompareManifests(const json& sealed, const json& now, std::vector<std::string>& problems) {
  for (const char* p : kParts) {
    if (sealed.value(p, "") != now.value(p, "")) {
      problems.push_back(std::string(PartName(p)) + " (\"" + p +
                         "\") was changed after the certificate was sealed");
    }
  }
  const json empty = json::object();
  auto entries = [&](const char* what, const char* kind) {
    const json& a = sealed.contains("report") ? sealed["report"].value(what, empty) : empty;
    const json& b = now["report"].value(what, empty);
    std::set<std::string> keys;
    for (auto it = a.begin(); it != a.end(); ++it) keys.insert(it.key());
    for (auto it = b.begin(); it != b.end(); ++it) keys.insert(it.key());
    for (const std::string& k : keys) {
      if (!a.contains(k)) {
        problems.push_back(std::string(kind) + " " + k + " was added after sealing");
      } else if (!b.contains(k)) {
        problems.push_back(std::string(kind) + " " + k + " was removed after sealing");
      } else if (a[k] != b[k]) {
        problems.push_back(std::string("the verdict of ") + kind + " " + k +
                           " was changed after the certificate was sealed");
      }
    }
  };
  entries("rules", "rule");
  entries("cases", "case");
  const std::string rest_a =
      sealed.contains("report") ? sealed["report"].value("rest", "") : std::string();
  if (rest_a != now["report"].value("rest", "")) {
    problems.push_back(
        "the report's summary (exit code, device, errors) was changed after the certificate was "
        "sealed");
  }
}

// The report without what the wall clock decides, for comparing verdicts.
json Judged(json report, bool evidence) {
  report.erase("wall_s");
  report.erase("target");
  if (!evidence) {
    report.erase("device");
    report.erase("target_caveats");
  }
  if (report.contains("cases") && report["cases"].is_array()) {
    for (json& c : report["cases"]) {
      c.erase("wall_s");
      if (evidence) continue;
      // Another run of the device: what the rules decided, not what they saw.
      for (const char* k :
           {"target_ms", "log", "last_positions", "position_range", "not_waited_for", "summary"}) {
        c.erase(k);
      }
      if (c.contains("rules") && c["rules"].is_array()) {
        for (json& r : c["rules"])
          r = {{"rule", r.value("rule", "?")}, {"status", r.value("status", "?")}};
      }
    }
  }
  if (!evidence && report.contains("rules") && report["rules"].is_array()) {
    for (json& r : report["rules"]) r.erase("why_not_exercised");
  }
  return report;
}

std::string Str(const json& j) { return j.is_string() ? j.get<std::string>() : j.dump(); }

}  // namespace

std::string MococheckVersion() { return MOCO_VERSION; }

std::string CatalogueSha256() {
  static const std::string digest = Digest(JudgedCatalogue());
  return digest;
}

size_t CatalogueRuleCount() { return RuleCount(); }

std::string CanonicalText(const json& j) {
  // Text a device sent that is not UTF-8 becomes U+FFFD here and in the file
  // alike, so the text read back has the same canonical form.
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string KeyId(std::string_view raw_public_key) {
  return Sha256Hex(raw_public_key).substr(0, 16);
}

json MakeCertificate(const CertificateParts& parts) {
  json cert;
  cert["format"] = std::string(kCertificateFormat);
  cert["mococheck"] = {{"version", MococheckVersion()}, {"made_at", parts.made_at}};
  cert["catalogue"] = {{"sha256", CatalogueSha256()}, {"rules", CatalogueRuleCount()}};
  cert["device"] = parts.device;
  cert["firmware"] = parts.firmware;
  cert["run"] = parts.run;
  cert["report"] = parts.report;
  const std::string packed = Deflate(parts.call_log);
  cert["transcript"] = {{"encoding", "mococheck-call-log/2+zlib+base64"},
                        {"bytes", parts.call_log.size()},
                        {"sha256", Sha256Hex(parts.call_log)},
                        {"data", Base64(packed)}};
  return cert;
}

std::optional<std::string> SealCertificate(json& cert, std::string_view private_pem) {
  std::string error;
  const auto public_pem = PublicKeyOf(private_pem, &error);
  if (!public_pem) return error;
  const auto raw = RawPublicKey(*public_pem, &error);
  if (!raw) return error;
  cert.erase("seal");
  const json manifest = Manifest(cert);
  const auto signature = Sign(private_pem, CanonicalText(manifest), &error);
  if (!signature) return error;
  cert["seal"] = {{"algorithm", "Ed25519"},
                  {"public_key", Base64(*raw)},
                  {"key_id", KeyId(*raw)},
                  {"signed", "the canonical text of \"manifest\" (sorted keys, no spaces)"},
                  {"manifest", manifest},
                  {"signature", Base64(*signature)}};
  return std::nullopt;
}

namespace {

CertificateCheck CheckFields(const json& cert, std::string_view public_pem) {
  CertificateCheck check;
  auto& problems = check.problems;
  if (!cert.is_object() || cert.value("format", "") != kCertificateFormat) {
    problems.push_back("not a mococheck certificate (its \"format\" is not " +
                       std::string(kCertificateFormat) + ")");
    return check;
  }
  std::string error;
  const auto raw_key = RawPublicKey(public_pem, &error);
  if (!raw_key) {
    problems.push_back("--key: " + error);
    return check;
  }
  const json seal = cert.value("seal", json::object());
  const auto sealed_key = FromBase64(seal.value("public_key", ""));
  const auto signature = FromBase64(seal.value("signature", ""));
  check.key_id = seal.value("key_id", "");
  if (!seal.is_object() || !seal.contains("manifest") || !sealed_key || !signature) {
    problems.push_back(
        "the certificate has no seal (no \"seal\" with a manifest, a public key "
        "and a signature): it was not made by 'mococheck certify --key'");
    return check;
  }
  if (*sealed_key != *raw_key) {
    problems.push_back("the certificate was sealed by key " + KeyId(*sealed_key) +
                       ", not by the key given (" + KeyId(*raw_key) +
                       "): ask its maker for their public key");
    return check;
  }
  if (!VerifySignature(*raw_key, CanonicalText(seal["manifest"]), *signature)) {
    problems.push_back(
        "the seal's signature does not match its manifest: the manifest or the signature was "
        "changed after sealing");
    return check;
  }
  json unsealed = cert;
  unsealed.erase("seal");
  CompareManifests(seal["manifest"], Manifest(unsealed), problems);
  const json catalogue = cert.value("catalogue", json::object());
  const std::string sealed_catalogue = catalogue.value("sha256", "");
  if (sealed_catalogue != CatalogueSha256()) {
    check.catalogue_differs = true;
    const json tool = cert.value("mococheck", json::object());
    problems.push_back("made with another rule catalogue: the certificate's is " +
                       sealed_catalogue.substr(0, 16) + " (mococheck " +
                       Str(tool.value("version", json("?"))) + ", " +
                       Str(catalogue.value("rules", json("?"))) + " rules), this mococheck's is " +
                       CatalogueSha256().substr(0, 16) + " (mococheck " + MococheckVersion() +
                       ", " + std::to_string(CatalogueRuleCount()) +
                       " rules); verify it with the mococheck that made it, or certify again");
  }
  if (!CallLogOf(cert, &error)) problems.push_back("the transcript: " + error);
  return check;
}

}  // namespace

CertificateCheck CheckCertificate(const json& cert, std::string_view public_pem) {
  try {
    return CheckFields(cert, public_pem);
  } catch (const json::exception& e) {
    // A field of the wrong type (a number where an object or text belongs).
    CertificateCheck check;
    check.problems.push_back(std::string("the certificate is malformed: ") + e.what());
    return check;
  }
}

std::optional<std::string> CallLogOf(const json& cert, std::string* error) {
  const json t = cert.value("transcript", json::object());
  if (!t.is_object() || !t.contains("data") || !t["data"].is_string() || !t.contains("bytes") ||
      !t["bytes"].is_number_unsigned()) {
    *error = "the certificate holds no transcript";
    return std::nullopt;
  }
  const uint64_t size = t["bytes"].get<uint64_t>();
  if (size > kMaxCallLogBytes) {
    *error = "it claims " + std::to_string(size) + " bytes, more than the " +
             std::to_string(kMaxCallLogBytes >> 20) + " MiB a certificate may hold";
    return std::nullopt;
  }
  const auto packed = FromBase64(t["data"].get<std::string>());
  if (!packed) {
    *error = "its data is not base64";
    return std::nullopt;
  }
  auto log = Inflate(*packed, static_cast<size_t>(size), error);
  if (!log) return std::nullopt;
  if (Sha256Hex(*log) != t.value("sha256", "")) {
    *error = "its bytes do not have the SHA-256 it gives";
    return std::nullopt;
  }
  return log;
}

std::vector<std::string> CompareVerdicts(const json& sealed_report, const json& replayed_report,
                                         bool evidence) {
  std::vector<std::string> out;
  const json a = Judged(sealed_report, evidence), b = Judged(replayed_report, evidence);
  auto rules_of = [](const json& r) {
    std::map<std::string, json> m;
    if (r.contains("rules") && r["rules"].is_array()) {
      for (const json& x : r["rules"]) m[x.value("id", "?")] = x;
    }
    return m;
  };
  const auto ra = rules_of(a), rb = rules_of(b);
  for (const auto& [id, x] : ra) {
    const auto it = rb.find(id);
    if (it == rb.end()) {
      out.push_back("rule " + id + ": sealed " + Str(x.value("status", json("?"))) +
                    ", not judged in the replay");
    } else if (x != it->second) {
      out.push_back("rule " + id + ": sealed " + Str(x.value("status", json("?"))) + " (" +
                    Str(x.value("cases_passed", json(0))) + " cases passed, " +
                    Str(x.value("cases_failed", json(0))) + " failed), replayed " +
                    Str(it->second.value("status", json("?"))) + " (" +
                    Str(it->second.value("cases_passed", json(0))) + " passed, " +
                    Str(it->second.value("cases_failed", json(0))) + " failed)");
    }
  }
  for (const auto& [id, x] : rb) {
    if (!ra.count(id)) {
      out.push_back("rule " + id + ": not in the certificate, replayed " +
                    Str(x.value("status", json("?"))));
    }
  }
  const json ca = a.value("cases", json::array()), cb = b.value("cases", json::array());
  const std::vector<std::string> ka = CaseKeys(ca), kb = CaseKeys(cb);
  for (size_t i = 0; i < ka.size() || i < kb.size(); ++i) {
    if (i >= ka.size()) {
      out.push_back("case " + kb[i] + ": not in the certificate");
    } else if (i >= kb.size()) {
      out.push_back("case " + ka[i] + ": did not run in the replay");
    } else if (ka[i] != kb[i]) {
      out.push_back("case " + std::to_string(i + 1) + ": sealed " + ka[i] + ", replayed " + kb[i]);
    } else if (ca[i] != cb[i]) {
      out.push_back("case " + ka[i] + ": sealed " + Str(ca[i].value("status", json("?"))) +
                    ", replayed " + Str(cb[i].value("status", json("?"))) +
                    (ca[i].value("status", json()) == cb[i].value("status", json())
                         ? " (its rules' outcomes or evidence differ)"
                         : ""));
    }
  }
  for (const char* k : {"exit_code", "must_failed", "target_error", "no_verdict", "device"}) {
    if (!evidence && std::string_view(k) == "device") continue;
    if (a.value(k, json()) != b.value(k, json())) {
      out.push_back(std::string(k) + ": sealed " + Str(a.value(k, json())) + ", replayed " +
                    Str(b.value(k, json())));
    }
  }
  return out;
}

CertificateTally TallyOf(const json& cert) {
  CertificateTally t;
  const json device = cert.value("device", json::object());
  const json report = cert.value("report", json::object());
  t.protocol = device.value("protocol", report.value("protocol", "?"));
  t.device = device.value("introduced", "");
  if (t.device.empty()) t.device = device.value("target", "?");
  t.passed = report.value("exit_code", 2) == 0;
  for (const json& r : report.value("rules", json::array())) {
    const std::string level = r.value("level", ""), status = r.value("status", "");
    if (status == "pass" || status == "fail" || status == "note") ++t.judged;
    if (level == "MUST") {
      t.must_passed += status == "pass";
      t.must_failed += status == "fail";
    } else if (level == "SHOULD") {
      t.should_passed += status == "pass";
      t.should_failed += status == "fail";
    }
  }
  return t;
}

namespace {
// Text in SVG and HTML.
std::string Escaped(std::string_view text) { return base::XmlEscape(text); }
}  // namespace

std::string CertificateBadge(const json& cert) {
  const CertificateTally t = TallyOf(cert);
  const std::string left = "mococheck " + t.protocol;
  const std::string right = std::string(t.passed ? "certified" : "FAILED") + " " +
                            std::to_string(t.must_passed) + "/" +
                            std::to_string(t.must_passed + t.must_failed) + " MUST";
  // About 6.5 px a character at 11 px Verdana, as badges are laid out.
  const int lw = static_cast<int>(left.size()) * 7 + 10;
  const int rw = static_cast<int>(right.size()) * 7 + 10;
  const char* color = t.passed ? "#4c1" : "#e05d44";
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(lw + rw) +
                    "\" height=\"20\" role=\"img\" aria-label=\"" + Escaped(left + ": " + right) +
                    "\">\n";
  svg += "<title>" + Escaped(left + ": " + right) + "</title>\n";
  svg += "<rect width=\"" + std::to_string(lw) + "\" height=\"20\" fill=\"#555\"/>\n";
  svg += "<rect x=\"" + std::to_string(lw) + "\" width=\"" + std::to_string(rw) +
         "\" height=\"20\" fill=\"" + color + "\"/>\n";
  svg +=
      "<g fill=\"#fff\" text-anchor=\"middle\" font-family=\"Verdana,DejaVu Sans,sans-serif\" "
      "font-size=\"11\">\n";
  svg += "<text x=\"" + std::to_string(lw / 2) + "\" y=\"14\">" + Escaped(left) + "</text>\n";
  svg += "<text x=\"" + std::to_string(lw + rw / 2) + "\" y=\"14\">" + Escaped(right) +
         "</text>\n</g>\n</svg>\n";
  return svg;
}

std::string CertificateSummary(const json& cert, const std::string& cert_name) {
  const CertificateTally t = TallyOf(cert);
  const json tool = cert.value("mococheck", json::object());
  const json catalogue = cert.value("catalogue", json::object());
  const json seal = cert.value("seal", json::object());
  const json fw = cert.value("firmware", json());
  std::string s = "**" + t.device + "** " + (t.passed ? "passed" : "did not pass") +
                  " the mococheck " + tool.value("version", "?") + " " + t.protocol +
                  " conformance suite";
  const std::string made = tool.value("made_at", "");
  if (!made.empty()) s += " on " + made.substr(0, 10);
  s += ": " + std::to_string(t.must_passed) + " MUST rules passed and " +
       std::to_string(t.must_failed) + " failed, " + std::to_string(t.should_passed) +
       " SHOULD rules passed and " + std::to_string(t.should_failed) + " failed (" +
       std::to_string(t.judged) + " rules judged; catalogue sha256 " +
       catalogue.value("sha256", "?").substr(0, 16) + ")";
  if (fw.is_object()) {
    s += ", firmware " + fw.value("file", "?") + " sha256 " + fw.value("sha256", "?").substr(0, 16);
  }
  s += ". The certificate `" + cert_name + "` is sealed by Ed25519 key " +
       seal.value("key_id", "?") + " and holds every verdict with its evidence and the whole " +
       "recorded exchange; check it with `mococheck verify " + cert_name +
       " --key KEY.pub --replay`.\n";
  return s;
}

namespace {

std::string CertificateHtmlSection(const json& cert, const std::string& cert_name, bool replayed) {
  const CertificateTally t = TallyOf(cert);
  const json tool = cert.value("mococheck", json::object());
  const json catalogue = cert.value("catalogue", json::object());
  const json seal = cert.value("seal", json::object());
  const json fw = cert.value("firmware", json());
  auto row = [](const std::string& k, const std::string& v) {
    return "<tr><th>" + Escaped(k) + "</th><td><code>" + Escaped(v) + "</code></td></tr>\n";
  };
  std::string s = "<section id=\"certificate\"><h2>Certificate " + Escaped(cert_name) + ": " +
                  (t.passed ? "PASS" : "FAIL") + (replayed ? ", verified" : ", sealed") +
                  "</h2>\n<table>\n";
  s += row("device", t.device + " (" + t.protocol + ")");
  s += row("made", tool.value("made_at", "?") + " by mococheck " + tool.value("version", "?"));
  s += row("rule catalogue", catalogue.value("sha256", "?") + " (" +
                                 Str(catalogue.value("rules", json("?"))) + " rules)");
  if (fw.is_object()) {
    s += row("firmware", fw.value("file", "?") + " sha256 " + fw.value("sha256", "?"));
  } else {
    // The manifest below still seals the empty part, as every certificate does.
    s += row("firmware", "none: the device under test ran no firmware image");
  }
  s += row("sealed by", "Ed25519 key " + seal.value("key_id", "?"));
  const json manifest = seal.value("manifest", json::object());
  for (const char* p : kParts) s += row(std::string("sha256 of ") + p, manifest.value(p, "?"));
  if (replayed) {
    s += "</table>\n<p>This page was rendered by <code>mococheck verify --replay</code> from the "
         "certificate's transcript, judged again: every verdict below is the sealed one.</p>\n"
         "</section>\n";
  } else {
    s += "</table>\n<p>This page was rendered by <code>mococheck certify</code> from the run it "
         "sealed. Check the certificate, and judge its transcript again, with <code>mococheck "
         "verify " +
         Escaped(cert_name) + " --key KEY.pub --replay</code>.</p>\n</section>\n";
  }
  return s;
}

}  // namespace

std::string CertificateHtmlPage(const RunReport& report, const json& cert,
                                const std::string& cert_name, bool replayed) {
  std::string page = HtmlReport(report);
  const size_t h1 = page.find("</h1>");
  page.insert(h1 == std::string::npos ? 0 : h1 + 6,
              CertificateHtmlSection(cert, cert_name, replayed));
  return page;
}

}  // namespace moco::conformance
