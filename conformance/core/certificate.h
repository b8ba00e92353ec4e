// A certificate (docs/certificates.md): one JSON file holding what a
// certifying run was (the device as it introduced itself, the firmware
// image's digest, mococheck's version and its rule catalogue's digest, the
// options), what it found (the run's JSON report: every rule's verdict with
// its evidence) and its whole exchange with the device (the call log of
// targets/recorded_target.h, compressed), sealed by an Ed25519 signature over
// a manifest of each part's SHA-256. A reader sees which part changed after
// sealing; the call log lets anyone judge the traffic again.
#ifndef MOCO_CONFORMANCE_CORE_CERTIFICATE_H_
#define MOCO_CONFORMANCE_CORE_CERTIFICATE_H_

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "conformance/core/run_report.h"

namespace moco::conformance {

inline constexpr std::string_view kCertificateFormat = "mococheck-certificate/1";
// The largest call log a certificate may hold once inflated (a full DMC run
// in virtual time logs a few MB).
inline constexpr size_t kMaxCallLogBytes = size_t{256} << 20;

// mococheck's version ("0.1.0").
std::string MococheckVersion();
// The SHA-256 of the rule catalogue this mococheck judges with (every rule's
// id, level, needs, title, clause and source, in the catalogue's order), and
// its number of rules.
std::string CatalogueSha256();
size_t CatalogueRuleCount();

// The parts of a certificate that its run gives.
struct CertificateParts {
  nlohmann::json device;    // {"target", "protocol", "introduced", "info"}
  nlohmann::json firmware;  // null, or {"file", "sha256", "bytes"}
  nlohmann::json run;       // the options, enough to run the suite again
  nlohmann::json report;    // JsonReport() of the run
  std::string call_log;     // RecordingTarget::log()
  std::string made_at;      // when the run ended, UTC: "2026-12-05T21:37:51Z"
};

// The certificate of `parts`, not yet sealed.
nlohmann::json MakeCertificate(const CertificateParts& parts);

// Seals `cert` with the Ed25519 private key in PEM: adds "seal" (the public
// key, its id, the manifest of every part's digest, the signature). An error
// message, or nullopt.
std::optional<std::string> SealCertificate(nlohmann::json& cert, std::string_view private_pem);

// The text a digest or signature is taken over: `j` dumped with sorted keys,
// no spaces, UTF-8 as is (bytes that are not UTF-8 as U+FFFD, as the
// certificate file holds them).
std::string CanonicalText(const nlohmann::json& j);

// The short id of a raw public key: the first 16 hex digits of its SHA-256.
std::string KeyId(std::string_view raw_public_key);

struct CertificateCheck {
  // Each a sentence naming what is wrong: the seal, a part changed after
  // sealing (the rule or case by name), another catalogue, a damaged
  // transcript. Empty: the certificate is intact and sealed by the key.
  std::vector<std::string> problems;
  bool catalogue_differs = false;
  std::string key_id;  // the sealing key's id, as the certificate gives it
};

// Checks `cert` against the public key in PEM (`public_pem`): the format,
// the signature over the manifest, each part against its sealed digest, the
// catalogue against this mococheck's, and that the transcript inflates to
// its sealed digest.
CertificateCheck CheckCertificate(const nlohmann::json& cert, std::string_view public_pem);

// The call log inside `cert`, inflated and checked against its digest;
// nullopt and `error` when it is missing or damaged.
std::optional<std::string> CallLogOf(const nlohmann::json& cert, std::string* error);

// How a replayed run's JSON report differs from the sealed one in what the
// rules decided: each rule's verdict and counts, each case's status and its
// rules' outcomes and evidence, the exit code (times on the wall clock are
// not verdicts and are left out). `evidence` false (another run of a device,
// whose times and positions differ run to run): each rule's and case's
// status only. One sentence per difference; empty when the verdicts are the
// same.
std::vector<std::string> CompareVerdicts(const nlohmann::json& sealed_report,
                                         const nlohmann::json& replayed_report,
                                         bool evidence = true);

// What a certificate's report says, counted: the rules by level that passed
// and failed, and the run's result.
struct CertificateTally {
  std::string protocol;  // "dfmoco"
  std::string device;    // as it introduced itself, else the target
  bool passed = false;   // exit code 0
  int must_passed = 0, must_failed = 0, should_passed = 0, should_failed = 0;
  int judged = 0;  // rules that passed, failed or were noted
};
CertificateTally TallyOf(const nlohmann::json& cert);

// A badge (SVG, 20 px high, in the style of README shields) naming the
// protocol and the result with its MUST count, derived from `cert`.
std::string CertificateBadge(const nlohmann::json& cert);
// One paragraph (Markdown) a vendor can paste into a README: the device, the
// result with its counts, the catalogue, the key, and how to check it.
// `cert_name`: the certificate's file name as published.
std::string CertificateSummary(const nlohmann::json& cert, const std::string& cert_name);

// The report page of `report` (HtmlReport) headed by the certificate's
// facts (the key, when it was made, the version, catalogue and firmware
// digests, each part's sealed digest): what `certify --html` writes for the
// run it sealed (`replayed` false) and `verify --replay --html` for the run
// it judged again from the certificate's transcript (`replayed` true).
std::string CertificateHtmlPage(const RunReport& report, const nlohmann::json& cert,
                                const std::string& cert_name, bool replayed);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_CERTIFICATE_H_
