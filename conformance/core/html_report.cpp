// The self-contained HTML report of mococheck (see report.h): no script, no
// network; per rule the spec clause and expected/observed evidence, the
// transcript around each failure, and for cases with position reports a plot
// of motor positions against time with a mark at every report (DMC v2
// MOTOR_GET_POSITION updates, "Motor Control"; DFMoco `mp` lines).
#include <algorithm>
#include <cstdio>
#include <map>
#include <set>
#include <string_view>

#include "base/format.h"
#include "conformance/core/report.h"
#include "conformance/core/transcript.h"

namespace moco::conformance {
namespace {

std::string Esc(std::string_view s) { return XmlEscape(s); }

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

using Series = PositionSeries;

// The motors that moved.
Series Moved(Series s) {
  // Only motors that moved.
  for (auto it = s.begin(); it != s.end();) {
    const auto& v = it->second;
    const bool moved = std::any_of(v.begin(), v.end(),
                                   [&](const auto& p) { return p.second != v.front().second; });
    it = moved ? std::next(it) : s.erase(it);
  }
  return s;
}

// The watched pins from t - half to t + half, one row per signal, a red line
// at t: what a step driver saw around a pin rule's failure.
std::string PulsesAround(const PinTrace& trace, TimeNs t, TimeNs half) {
  constexpr double kW = 720, kL = 90, kR = 10, kRow = 22, kHigh = 14;
  const TimeNs a = std::max<TimeNs>(0, t - half), b = t + half;
  const double h = 20 + kRow * static_cast<double>(trace.signals.size());
  auto x = [&](TimeNs v) {
    return kL + (kW - kL - kR) * static_cast<double>(std::clamp(v, a, b) - a) /
                    static_cast<double>(std::max<TimeNs>(1, b - a));
  };
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + Num(kW) + "\" height=\"" +
                  Num(h) + "\" font-family=\"monospace\" font-size=\"11\">\n";
  for (size_t i = 0; i < trace.signals.size(); ++i) {
    const PinSignal& sig = trace.signals[i];
    const double base = 10 + kRow * static_cast<double>(i + 1);
    auto y = [&](bool level) { return level ? base - kHigh : base; };
    s += "<text x=\"2\" y=\"" + Num(base) + "\">" + Esc(sig.name) + "</text>\n";
    bool level = sig.LevelAt(a);
    std::string pts = Num(x(a)) + "," + Num(y(level));
    auto it = std::upper_bound(sig.edges.begin(), sig.edges.end(), a,
                               [](TimeNs v, const PinEdge& e) { return v < e.t_ns; });
    size_t drawn = 0;
    for (; it != sig.edges.end() && it->t_ns <= b && drawn < 2000; ++it, ++drawn) {
      pts += " " + Num(x(it->t_ns)) + "," + Num(y(level));
      level = it->level;
      pts += " " + Num(x(it->t_ns)) + "," + Num(y(level));
    }
    pts += " " + Num(x(b)) + "," + Num(y(level));
    s += "<polyline fill=\"none\" stroke=\"#1f77b4\" points=\"" + pts + "\"/>\n";
  }
  s += "<line x1=\"" + Num(x(t)) + "\" y1=\"4\" x2=\"" + Num(x(t)) + "\" y2=\"" + Num(h) +
       "\" stroke=\"#d62728\"/>\n";
  s += "</svg>\n<p>pins from " + Esc(base::Ms(a, 3)) + " to " + Esc(base::Ms(b, 3)) +
       " (red: the failure)</p>\n";
  return s;
}

std::string Plot(const Series& series) {
  constexpr double kW = 720, kH = 260, kL = 70, kR = 20, kT = 20, kB = 40;
  TimeNs t0 = INT64_MAX, t1 = INT64_MIN;
  int64_t p0 = INT64_MAX, p1 = INT64_MIN;
  for (const auto& [m, v] : series) {
    for (const auto& [t, p] : v) {
      t0 = std::min(t0, t), t1 = std::max(t1, t);
      p0 = std::min(p0, p), p1 = std::max(p1, p);
    }
  }
  if (t1 <= t0) t1 = t0 + 1;
  if (p1 <= p0) p1 = p0 + 1;
  auto x = [&](TimeNs t) {
    return kL + (kW - kL - kR) * static_cast<double>(t - t0) / static_cast<double>(t1 - t0);
  };
  auto y = [&](int64_t p) {
    return kH - kB - (kH - kT - kB) * static_cast<double>(p - p0) / static_cast<double>(p1 - p0);
  };
  static constexpr const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                            "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + Num(kW) + "\" height=\"" +
                  Num(kH) + "\" role=\"img\" aria-label=\"motor positions against time\">\n";
  s += "<rect x=\"" + Num(kL) + "\" y=\"" + Num(kT) + "\" width=\"" + Num(kW - kL - kR) +
       "\" height=\"" + Num(kH - kT - kB) + "\" fill=\"#fafafa\" stroke=\"#999\"/>\n";
  s += "<text x=\"" + Num(kL) + "\" y=\"" + Num(kH - 22) + "\" font-size=\"11\">" +
       Esc(base::Ms(t0, 3)) + "</text>\n";
  s += "<text x=\"" + Num(kW - kR) + "\" y=\"" + Num(kH - 22) +
       "\" font-size=\"11\" text-anchor=\"end\">" + Esc(base::Ms(t1, 3)) + "</text>\n";
  s += "<text x=\"" + Num((kW + kL) / 2) + "\" y=\"" + Num(kH - 6) +
       "\" font-size=\"11\" text-anchor=\"middle\">time on the target's clock</text>\n";
  s += "<text x=\"" + Num(kL - 4) + "\" y=\"" + Num(kT + 10) +
       "\" font-size=\"11\" text-anchor=\"end\">" + std::to_string(p1) + "</text>\n";
  s += "<text x=\"" + Num(kL - 4) + "\" y=\"" + Num(kH - kB) +
       "\" font-size=\"11\" text-anchor=\"end\">" + std::to_string(p0) + "</text>\n";
  s += "<text x=\"12\" y=\"" + Num((kH - kB + kT) / 2) +
       "\" font-size=\"11\" transform=\"rotate(-90 12 " + Num((kH - kB + kT) / 2) +
       ")\" text-anchor=\"middle\">steps</text>\n";
  size_t k = 0;
  for (const auto& [motor, v] : series) {
    const char* color = kColors[k++ % std::size(kColors)];
    s += "<polyline fill=\"none\" stroke=\"" + std::string(color) +
         "\" stroke-width=\"1.5\" points=\"";
    for (const auto& [t, p] : v) s += Num(x(t)) + "," + Num(y(p)) + " ";
    s += "\"/>\n";
    for (const auto& [t, p] : v) {
      s += "<circle cx=\"" + Num(x(t)) + "\" cy=\"" + Num(y(p)) + "\" r=\"2\" fill=\"" + color +
           "\"><title>motor " + std::to_string(motor) + " at " + std::to_string(p) + " steps, " +
           Esc(base::Ms(t, 3)) + "</title></circle>\n";
    }
    s += "<text x=\"" + Num(kL + 8 + 80.0 * static_cast<double>(k - 1)) + "\" y=\"" + Num(kT + 14) +
         "\" font-size=\"11\" fill=\"" + color + "\">motor " + std::to_string(motor) + " (" +
         std::to_string(v.size()) + " reports)</text>\n";
  }
  s += "</svg>\n";
  return s;
}

std::string TranscriptAround(const std::vector<TrafficLine>& lines, TimeNs t_ns) {
  const auto it = std::lower_bound(lines.begin(), lines.end(), t_ns,
                                   [](const TrafficLine& l, TimeNs t) { return l.t_ns < t; });
  const size_t at = static_cast<size_t>(it - lines.begin());
  const size_t from = at > 10 ? at - 10 : 0;
  const size_t to = std::min(lines.size(), at + 6);
  std::string s = "<pre class=\"tx\">";
  for (size_t i = from; i < to; ++i) {
    const TrafficLine& l = lines[i];
    char head[48];
    std::snprintf(head, sizeof head, "%12.3f ms  %s  ", static_cast<double>(l.t_ns) / 1e6,
                  l.from_host ? "host -&gt;" : "&lt;- dev");
    s += std::string(l.problem ? "<b class=\"bad\">" : (i == at ? "<b>" : "<span>")) + head +
         Esc(l.text) + (l.problem || i == at ? "</b>" : "</span>") + "\n";
  }
  if (from == to) s += "(no traffic)\n";
  return s + "</pre>\n";
}

}  // namespace

std::string HtmlReport(const RunReport& report) {
  const auto counts = report.RuleCounts();
  auto count = [&](Status st) {
    auto it = counts.find(st);
    return it == counts.end() ? size_t{0} : it->second;
  };
  const bool failed = report.MustFailed();
  std::string s;
  s += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
  s += "<title>mococheck: " + Esc(report.target) + "</title>\n<style>\n";
  s += "body{font:14px/1.4 system-ui,sans-serif;margin:2em;max-width:70em;color:#222}\n"
       "h1{font-size:1.4em}h2{font-size:1.15em;margin-top:2em}table{border-collapse:collapse}\n"
       "td,th{border:1px solid #ccc;padding:2px 6px;text-align:left;vertical-align:top}\n"
       ".pass{color:#1a7f37}.fail{color:#c62828;font-weight:bold}.note{color:#8250df}"
       ".na{color:#888}.verdict{font-size:1.3em;padding:.4em .8em;display:inline-block;"
       "border-radius:4px}.ok{background:#dafbe1}.ko{background:#ffebe9}\n"
       "pre.tx{background:#f6f8fa;padding:.5em;overflow-x:auto;font-size:12px}"
       "b.bad{color:#c62828}blockquote{margin:.3em 0 .3em 1em;color:#555}"
       "details{margin:.3em 0}td.id{white-space:nowrap}\n</style></head><body>\n";
  s += "<h1>mococheck conformance report</h1>\n";
  const std::string verdict =
      !report.target_error.empty()
          ? "ko\">TARGET ERROR: " + Esc(report.target_error) + " (no verdict on the device)"
      : report.interrupted_by != 0
          ? "ko\">INTERRUPTED by signal " + std::to_string(report.interrupted_by) +
                (report.interrupted_case.empty() ? std::string()
                                                 : " during " + Esc(report.interrupted_case)) +
                " (no verdict)"
      : failed ? "ko\">FAIL: a MUST rule failed"
               : "ok\">PASS: every MUST rule held";
  s += "<p><span class=\"verdict " + verdict + "</span></p>\n";
  s += "<table><tr><th>target</th><td>" + Esc(report.target) + "</td></tr>\n";
  s += "<tr><th>protocol</th><td>" + Esc(report.protocol) + "</td></tr>\n";
  s += "<tr><th>device</th><td>" +
       Esc(report.device.empty() ? "did not introduce itself" : report.device) + "</td></tr>\n";
  s += "<tr><th>seed</th><td>" + std::to_string(report.options.random.seed) + "</td></tr>\n";
  s += "<tr><th>rules</th><td>" + std::to_string(count(Status::kPass)) + " pass, " +
       std::to_string(count(Status::kFail)) + " fail, " + std::to_string(count(Status::kNoted)) +
       " noted, " + std::to_string(count(Status::kNotApplicable)) + " not applicable, " +
       std::to_string(count(Status::kNotExercised)) + " not exercised</td></tr>\n";
  s += "<tr><th>time</th><td>" + Num(report.wall_s) + " s</td></tr></table>\n";
  if (!report.target_caveats.empty()) {
    s += "<h2>Target caveats</h2>\n<ul>\n";
    for (const std::string& caveat : report.target_caveats) s += "<li>" + Esc(caveat) + "</li>\n";
    s += "</ul>\n";
  }

  // Rules: failures first. A rule links to its first finding below; a rule with
  // none (passed, or not judged) has nothing to link to.
  std::set<std::string> findings;
  for (const CaseResult& c : report.cases) {
    if (!c.applicable) continue;
    for (const auto& [id, o] : c.outcomes) {
      if (o.status != Status::kPass) findings.insert(id);
    }
  }
  s += "<h2>Rules</h2>\n<table><tr><th>id</th><th>level</th><th>status</th><th>cases "
       "failed/passed</th><th>rule</th></tr>\n";
  std::vector<std::pair<std::string, RuleSummary>> rules(report.rules.begin(), report.rules.end());
  std::stable_sort(rules.begin(), rules.end(), [](const auto& a, const auto& b) {
    return (a.second.status == Status::kFail) > (b.second.status == Status::kFail);
  });
  for (const auto& [id, sum] : rules) {
    const Rule* r = FindRule(id);
    const std::string cls = sum.status == Status::kFail    ? "fail"
                            : sum.status == Status::kPass  ? "pass"
                            : sum.status == Status::kNoted ? "note"
                                                           : "na";
    const std::string cell =
        findings.contains(id) ? "<a href=\"#" + Esc(id) + "\">" + Esc(id) + "</a>" : Esc(id);
    s += "<tr><td class=\"id\">" + cell + "</td><td>" + Esc(r ? LevelName(r->level) : "?") +
         "</td><td class=\"" + cls + "\">" + Esc(StatusName(sum.status)) + "</td><td>" +
         std::to_string(sum.cases_failed) + "/" + std::to_string(sum.cases_passed) + "</td><td>" +
         Esc(r ? r->title : "") + "</td></tr>\n";
  }
  s += "</table>\n";

  // Cases. The first finding of each rule carries the rule's id as its anchor.
  s += "<h2>Cases</h2>\n";
  std::set<std::string> anchored;
  for (const CaseResult& c : report.cases) {
    const std::string full = c.suite + "/" + c.name;
    if (!c.applicable) {
      s += "<p class=\"na\">n/a " + Esc(full) + ": " + Esc(c.not_applicable_because) + "</p>\n";
      continue;
    }
    const bool case_failed = c.MustFailed();
    s += std::string("<details") + (case_failed ? " open" : "") + "><summary><span class=\"" +
         (case_failed ? "fail\">FAIL" : "pass\">ok") + "</span> " + Esc(full) + " &mdash; " +
         Esc(c.summary) + " (" + Esc(base::Ms(c.target_ns, 3)) + ")</summary>\n";
    if (!c.not_waited_for.empty()) {
      s += "<p class=\"note\">" + Esc(c.not_waited_for) + "</p>\n";
    }
    const std::vector<TrafficLine> lines =
        DecodeTraffic(wire::ParseProtocol(report.protocol).value_or(Protocol::kDmc), c.traffic);
    for (const auto& [id, o] : c.outcomes) {
      if (o.status == Status::kPass) continue;
      const Rule* r = FindRule(id);
      const std::string anchor =
          anchored.insert(id).second ? " id=\"" + Esc(id) + "\"" : std::string();
      s += "<h3" + anchor + " class=\"" + (o.status == Status::kFail ? "fail" : "note") + "\">" +
           Esc(StatusName(o.status)) + " " + Esc(id) + " [" + Esc(r ? LevelName(r->level) : "?") +
           "] " + Esc(r ? r->title : "") + "</h3>\n";
      if (r) {
        s += "<blockquote>&ldquo;" + Esc(r->clause) + "&rdquo; (" + Esc(r->source) +
             ")</blockquote>\n";
      }
      for (const Evidence& e : o.evidence) {
        s += "<table><tr><th>expected</th><td>" + Esc(e.expected) +
             "</td></tr><tr><th>observed</th><td>" + Esc(e.observed) +
             "</td></tr><tr><th>at</th><td>" + Esc(base::Ms(e.t_ns, 3)) + "</td></tr>";
        if (!e.hex.empty()) s += "<tr><th>bytes</th><td><code>" + Esc(e.hex) + "</code></td></tr>";
        s += "</table>\n" + TranscriptAround(lines, e.t_ns);
        if (c.pins && id.find("-PIN-") != std::string::npos) {
          // Pulse timing shows at 100 us; counts, rates and reversals over 50 ms.
          const bool timing = id.ends_with("003") || id.ends_with("004") || id.ends_with("005");
          s += PulsesAround(*c.pins, e.t_ns, (timing ? 100 : 50'000) * sim::kNsPerUs);
        }
      }
      if (o.failures > o.evidence.size()) {
        s += "<p>(" + std::to_string(o.failures - o.evidence.size()) + " more)</p>\n";
      }
    }
    size_t passed = 0;
    for (const auto& [id, o] : c.outcomes) passed += o.status == Status::kPass;
    s += "<p>" + std::to_string(passed) + " rule(s) held in this case.</p>\n";
    const Series series = Moved(c.positions);
    size_t reports = 0;
    for (const auto& [m, v] : series) reports += v.size();
    if (reports >= 3) s += "<p>Motor positions as the device reported them:</p>\n" + Plot(series);
    for (const std::string& l : c.log) s += "<pre class=\"tx\">" + Esc(l) + "</pre>\n";
    s += "</details>\n";
  }
  s += "<p class=\"na\">Generated by mococheck. Levels: MUST failures fail the run, SHOULD "
       "failures are reported, NOTE marks a reading the spec leaves open.</p>\n</body></html>\n";
  return s;
}

}  // namespace moco::conformance
