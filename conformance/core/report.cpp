// mococheck reports (see report.h).
#include "conformance/core/report.h"

#include "base/format.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "base/file_io.h"

namespace moco::conformance {
namespace {

std::string EvidenceText(const Evidence& e) {
  std::string s =
      "expected: " + e.expected + "\nobserved: " + e.observed + "\nat: " + base::Ms(e.t_ns, 3);
  if (!e.hex.empty()) s += "\nbytes: " + e.hex;
  return s;
}

}  // namespace

std::string ConsoleTitle(const std::string& target, const std::string& protocol_name) {
  const auto protocol = wire::ParseProtocol(protocol_name);
  return "mococheck: " + target + " (" +
         std::string(protocol ? wire::Info(*protocol).title : protocol_name) + ")\n";
}

std::string ConsoleDevice(const RunReport& report) {
  return (report.device.empty() ? "device: no answer to the introduction\n"
                                : "device: " + report.device + "\n") +
         "\n";
}

std::string ConsoleReport(const RunReport& report, bool verbose) {
  std::string s = ConsoleTitle(report.target, report.protocol) + ConsoleDevice(report);
  for (const CaseResult& c : report.cases) s += ConsoleCase(c, verbose);
  return s + ConsoleSummary(report, verbose);
}

std::string ConsoleCase(const CaseResult& c, bool verbose) {
  std::string s;
  {
    const std::string full = c.suite + "/" + c.name;
    if (!c.applicable) {
      s += "  n/a   " + full + " (" + c.not_applicable_because + ")\n";
      return s;
    }
    size_t failed = 0, passed = 0, noted = 0;
    for (const auto& [id, o] : c.outcomes) {
      if (o.status == Status::kFail)
        ++failed;
      else if (o.status == Status::kNoted)
        ++noted;
      else
        ++passed;
    }
    s += std::string(c.MustFailed() ? "  FAIL  "
                     : failed       ? "  warn  "
                                    : "  ok    ") +
         full + "  (" + std::to_string(passed) + " rules passed" +
         (failed ? ", " + std::to_string(failed) + " failed" : "") +
         (noted ? ", " + std::to_string(noted) + " noted" : "") + "; " + base::Ms(c.target_ns, 3) +
         ")\n";
    if (!c.not_waited_for.empty()) s += "        " + c.not_waited_for + "\n";
    for (const auto& [id, o] : c.outcomes) {
      if (o.status == Status::kPass) {
        if (verbose) s += "        pass " + id + "\n";
        continue;
      }
      const Rule* r = FindRule(id);
      s += "        " + std::string(StatusName(o.status)) + " " + id + " [" +
           std::string(r ? LevelName(r->level) : "?") + "] " + std::string(r ? r->title : "") +
           "\n";
      if (r)
        s +=
            "          spec: \"" + std::string(r->clause) + "\" (" + std::string(r->source) + ")\n";
      for (const Evidence& e : o.evidence) {
        std::string t = EvidenceText(e);
        size_t pos = 0;
        while ((pos = t.find('\n', pos)) != std::string::npos)
          t.replace(pos, 1, "\n          "), pos += 11;
        s += "          " + t + "\n";
      }
      if (o.failures > o.evidence.size()) {
        s += "          (" + std::to_string(o.failures - o.evidence.size()) + " more)\n";
      }
    }
    for (const std::string& line : c.log) {
      if (!(verbose || c.MustFailed() || c.suite == "random")) continue;
      std::string indented = line;
      for (size_t pos = 0; (pos = indented.find('\n', pos)) != std::string::npos; pos += 9) {
        if (pos + 1 == indented.size()) break;
        indented.replace(pos, 1, "\n        ");
      }
      s += "        " + indented + (indented.empty() || indented.back() != '\n' ? "\n" : "");
    }
  }
  return s;
}

std::string ConsoleSummary(const RunReport& report, bool verbose) {
  std::string s;
  const auto counts = report.RuleCounts();
  auto count = [&](Status st) {
    auto it = counts.find(st);
    return it == counts.end() ? size_t{0} : it->second;
  };
  size_t must_failed = 0, should_failed = 0;
  for (const auto& [id, r] : report.rules) {
    if (r.status != Status::kFail) continue;
    const Rule* rule = FindRule(id);
    (rule && rule->level == Level::kMust ? must_failed : should_failed)++;
  }
  s += "\nrules: " + std::to_string(count(Status::kPass)) + " passed, " +
       std::to_string(count(Status::kFail)) + " failed (" + std::to_string(must_failed) +
       " MUST, " + std::to_string(should_failed) + " SHOULD), " +
       std::to_string(count(Status::kNoted)) + " noted, " +
       std::to_string(count(Status::kNotApplicable)) + " not applicable, " +
       std::to_string(count(Status::kNotExercised)) + " not exercised\n";
  // Without a verdict (a target error, an interrupted run) what was not
  // exercised says nothing of the rules: one line, not one per rule.
  const bool no_verdict = !report.target_error.empty() || report.interrupted_by != 0;
  if (no_verdict && count(Status::kNotExercised) > 0) {
    s += "  " + std::to_string(count(Status::kNotExercised)) +
         " rule(s) not exercised: the run has no verdict (below)\n";
  }
  for (const auto& [id, r] : report.rules) {
    if (r.status == Status::kNotExercised && no_verdict) continue;
    if (r.status == Status::kNotExercised) {
      // Always with its reason: a rule nobody judged is as much a finding as
      // one that failed.
      s += "  " + std::string(StatusName(r.status)) + " " + id + ": " + r.why_not_exercised + "\n";
    } else if (r.status == Status::kFail || (verbose && r.status != Status::kPass)) {
      const Rule* rule = FindRule(id);
      s += "  " + std::string(StatusName(r.status)) + " " + id +
           (r.status == Status::kFail && rule ? " [" + std::string(LevelName(rule->level)) + "]"
                                              : std::string()) +
           "\n";
    }
  }
  char wall[64];
  std::snprintf(wall, sizeof wall, "%.2f s", report.wall_s);
  if (!report.target_error.empty()) {
    s += "target error: " + report.target_error + "\n";
  }
  for (const std::string& caveat : report.target_caveats) s += "target caveat: " + caveat + "\n";
  if (report.interrupted_by != 0) {
    s += "interrupted by signal " + std::to_string(report.interrupted_by) + " after " +
         std::to_string(report.cases.size()) + " case(s)" +
         (report.interrupted_case.empty()
              ? std::string()
              : ", during " + report.interrupted_case + " (cut short: no verdict)") +
         "; the rest did not run\n";
  }
  if (report.target_error.empty() && report.interrupted_by == 0 && !report.JudgedAnyRule()) {
    s += report.NoVerdictReason() + "\n";
  }
  const char* verdict = !report.target_error.empty() ? "TARGET ERROR (no verdict on the device)"
                        : report.interrupted_by != 0 ? "INTERRUPTED (no verdict)"
                        : !report.JudgedAnyRule()    ? "NO VERDICT (no rule was judged)"
                        : report.MustFailed()        ? "FAIL (a MUST rule failed)"
                                                     : "PASS";
  s += std::string("result: ") + verdict + " in " + wall + "\n";
  return s;
}

nlohmann::json JsonReport(const RunReport& report) {
  using nlohmann::json;
  json j;
  j["tool"] = "mococheck";
  j["protocol"] = report.protocol;
  j["target"] = report.target;
  j["seed"] = report.options.random.seed;
  j["rules_filter"] = report.options.rules;
  j["shard"] = std::to_string(report.options.shard_index + 1) + "/" +
               std::to_string(report.options.shard_count);
  j["device"] = report.device.empty() ? json(nullptr) : report.device_info;
  auto evidence = [](const RuleOutcome& o) {
    json a = json::array();
    for (const Evidence& e : o.evidence) {
      a.push_back(
          {{"expected", e.expected}, {"observed", e.observed}, {"bytes", e.hex}, {"t_ns", e.t_ns}});
    }
    return a;
  };
  json cases = json::array();
  for (const CaseResult& c : report.cases) {
    json jc = {{"suite", c.suite}, {"name", c.name}, {"summary", c.summary}};
    if (!c.applicable) {
      jc["status"] = "n/a";
      jc["reason"] = c.not_applicable_because;
    } else {
      jc["status"] = c.MustFailed() ? "fail" : "pass";
      jc["target_ms"] = static_cast<double>(c.target_ns) / 1e6;
      if (!c.not_waited_for.empty()) jc["not_waited_for"] = c.not_waited_for;
      jc["wall_s"] = c.wall_s;
      json rules = json::array();
      for (const auto& [id, o] : c.outcomes) {
        rules.push_back({{"rule", id},
                         {"status", StatusName(o.status)},
                         {"checks", o.checks},
                         {"failures", o.failures},
                         {"evidence", evidence(o)}});
      }
      jc["rules"] = rules;
      // The last position each motor was reported at ({"1": 6000}).
      // ... and the lowest and highest ({"1": [0, 6000]}).
      json last = json::object(), range = json::object();
      for (const auto& [motor, series] : c.positions) {
        if (series.empty()) continue;
        last[std::to_string(motor)] = series.back().second;
        int64_t lo = series.front().second, hi = lo;
        for (const auto& [t, p] : series) lo = std::min(lo, p), hi = std::max(hi, p);
        range[std::to_string(motor)] = {lo, hi};
      }
      jc["last_positions"] = last;
      jc["position_range"] = range;
      jc["log"] = c.log;
    }
    cases.push_back(jc);
  }
  j["cases"] = cases;
  json rules = json::array();
  for (const auto& [id, r] : report.rules) {
    const Rule* rule = FindRule(id);
    json jr = {{"id", id},
               {"level", rule ? LevelName(rule->level) : "?"},
               {"status", StatusName(r.status)},
               {"cases_passed", r.cases_passed},
               {"cases_failed", r.cases_failed}};
    if (r.status == Status::kNotExercised) jr["why_not_exercised"] = r.why_not_exercised;
    rules.push_back(std::move(jr));
  }
  j["rules"] = rules;
  j["must_failed"] = report.MustFailed();
  j["target_error"] = report.target_error.empty() ? json(nullptr) : json(report.target_error);
  j["target_caveats"] = report.target_caveats;
  j["interrupted_by_signal"] = report.interrupted_by;
  j["interrupted_case"] =
      report.interrupted_case.empty() ? json(nullptr) : json(report.interrupted_case);
  const std::string no_verdict = report.NoVerdictReason();
  j["no_verdict"] = no_verdict.empty() ? json(nullptr) : json(no_verdict);
  j["exit_code"] = ExitCode(report);
  j["wall_s"] = report.wall_s;
  return j;
}

std::string JunitReport(const RunReport& report) {
  size_t tests = 0, failures = 0, must_failures = 0, skipped = 0;
  std::string body;
  for (const CaseResult& c : report.cases) {
    const std::string cls = "mococheck." + report.protocol + "." + c.suite + "." + c.name;
    if (!c.applicable) {
      body += "    <testcase classname=\"" + XmlEscape(cls) + "\" name=\"(case)\" time=\"0\">\n";
      body += "      <skipped message=\"not applicable: " + XmlEscape(c.not_applicable_because) +
              "\"/>\n";
      body += "    </testcase>\n";
      ++tests;
      ++skipped;
      continue;
    }
    for (const auto& [id, o] : c.outcomes) {
      ++tests;
      const Rule* r = FindRule(id);
      const std::string level(r ? LevelName(r->level) : "?");
      body += "    <testcase classname=\"" + XmlEscape(cls) + "\" name=\"" + XmlEscape(id) +
              "\" time=\"" + std::to_string(c.wall_s) + "\">\n";
      if (o.status == Status::kFail && r && r->level != Level::kNote) {
        // Both MUST and SHOULD failures are <failure> elements, where CI
        // dashboards look; the type says which (docs/files.md): only MUST
        // failures set the exit code, and the suite's must_failures property
        // counts them.
        ++failures;
        must_failures += r->level == Level::kMust;
        body += "      <failure type=\"" + level + "\" message=\"" +
                XmlEscape(level + " " + std::string(r->title)) + "\">";
        for (const Evidence& e : o.evidence) body += XmlEscape(EvidenceText(e)) + "\n";
        body += "</failure>\n";
      } else if (o.status != Status::kPass) {
        body += "      <system-out>" +
                XmlEscape(std::string(StatusName(o.status)) + " (" + level + "): ");
        for (const Evidence& e : o.evidence) body += XmlEscape(EvidenceText(e)) + "\n";
        body += "</system-out>\n";
      }
      body += "    </testcase>\n";
    }
  }
  // A run without a verdict is an error of the whole suite, not a passing one.
  size_t errors = 0;
  const std::string no_verdict = report.NoVerdictReason();
  if (!no_verdict.empty()) {
    ++tests;
    ++errors;
    body += "    <testcase classname=\"mococheck." + report.protocol +
            "\" name=\"(run)\" time=\"0\">\n      <error message=\"" + XmlEscape(no_verdict) +
            "\"/>\n    </testcase>\n";
  }
  std::string s = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  s += "<testsuites name=\"mococheck\" tests=\"" + std::to_string(tests) + "\" failures=\"" +
       std::to_string(failures) + "\" errors=\"" + std::to_string(errors) + "\">\n";
  s += "  <testsuite name=\"mococheck." + report.protocol + "\" tests=\"" + std::to_string(tests) +
       "\" failures=\"" + std::to_string(failures) + "\" errors=\"" + std::to_string(errors) +
       "\" skipped=\"" + std::to_string(skipped) + "\" time=\"" + std::to_string(report.wall_s) +
       "\">\n";
  s += "    <properties><property name=\"target\" value=\"" + XmlEscape(report.target) +
       "\"/><property name=\"seed\" value=\"" + std::to_string(report.options.random.seed) +
       "\"/><property name=\"must_failures\" value=\"" + std::to_string(must_failures) +
       "\"/><property name=\"should_failures\" value=\"" +
       std::to_string(failures - must_failures) + "\"/><property name=\"exit_code\" value=\"" +
       std::to_string(ExitCode(report)) + "\"/></properties>\n";
  s += body;
  s += "  </testsuite>\n</testsuites>\n";
  return s;
}

std::string WriteAtomically(const std::string& path, const std::string& text) {
  return base::WriteFileAtomically(path, text).value_or("");
}

}  // namespace moco::conformance
