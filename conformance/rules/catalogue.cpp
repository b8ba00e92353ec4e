// The rule catalogue across protocols: levels, lookups, filters and
// the catalogue's exports. Each protocol's rules are its own file
// (dmc_rules.cpp, dfmoco_rules.cpp, stackshot_rules.cpp, pin_rules.cpp).
#include "conformance/rules/catalogue.h"

#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <unordered_map>

namespace moco::conformance {

std::string_view LevelName(Level level) {
  switch (level) {
    case Level::kMust:
      return "MUST";
    case Level::kShould:
      return "SHOULD";
    case Level::kNote:
      return "NOTE";
  }
  return "?";
}

const std::vector<Rule>& RulesFor(Protocol p) {
  for (const RuleSet& set : kRuleSets) {
    if (set.protocol == p) return set.rules();
  }
  static const std::vector<Rule> kNone;  // a protocol without rules of its own
  return kNone;
}

size_t RuleCount() {
  size_t n = 0;
  for (Protocol p : kAllProtocols) n += RulesFor(p).size();
  return n;
}

const Rule* FindRule(std::string_view id) {
  // Looked up on every check a run or a fuzz campaign makes: an index built
  // once over the catalogue's static tables (which never move).
  static const std::unordered_map<std::string_view, const Rule*> index = [] {
    std::unordered_map<std::string_view, const Rule*> m;
    for (Protocol p : kAllProtocols) {
      for (const Rule& r : RulesFor(p)) m.emplace(r.id, &r);
    }
    return m;
  }();
  const auto it = index.find(id);
  return it == index.end() ? nullptr : it->second;
}

namespace {

bool GlobOne(std::string_view p, std::string_view t) {
  size_t pi = 0, ti = 0, star = std::string_view::npos, mark = 0;
  while (ti < t.size()) {
    if (pi < p.size() && (p[pi] == '?' || p[pi] == t[ti])) {
      ++pi;
      ++ti;
    } else if (pi < p.size() && p[pi] == '*') {
      star = pi++;
      mark = ti;
    } else if (star != std::string_view::npos) {
      pi = star + 1;
      ti = ++mark;
    } else {
      return false;
    }
  }
  while (pi < p.size() && p[pi] == '*') ++pi;
  return pi == p.size();
}

std::string Escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '|')
      out += "\\|";
    else
      out += c;
  }
  return out;
}

}  // namespace

namespace {

struct RuleTables {
  std::map<std::string_view, std::vector<std::string_view>> proofs;
  std::map<std::string_view, std::string_view> reasons;
  std::vector<std::string> problems;
};

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) {
    s.remove_prefix(1);
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

// Reads "ID<tab>value" lines ('#' comments and blank lines skipped).
template <typename Add>
void ReadTable(std::string_view text, const char* name, std::vector<std::string>& problems,
               Add add) {
  size_t line_no = 0;
  while (!text.empty()) {
    const size_t nl = text.find('\n');
    const std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    if (Trim(line).empty() || Trim(line).front() == '#') continue;
    const size_t tab = line.find('\t');
    const std::string where = std::string(name) + " line " + std::to_string(line_no);
    if (tab == std::string_view::npos || Trim(line.substr(tab + 1)).empty()) {
      problems.push_back(where + ": expected RULE-ID<tab>text");
      continue;
    }
    const std::string_view id = Trim(line.substr(0, tab));
    if (FindRule(id) == nullptr) {
      problems.push_back(where + ": no rule " + std::string(id));
      continue;
    }
    add(where, FindRule(id)->id, Trim(line.substr(tab + 1)));
  }
}

const RuleTables& Tables() {
  static const RuleTables tables = [] {
    RuleTables t;
    for (const detail::RuleTableText& table : detail::RuleTableTexts()) {
      const std::string proofs = "proofs/" + std::string(table.protocol) + ".tsv";
      ReadTable(table.proofs, proofs.c_str(), t.problems,
                [&](const std::string&, std::string_view id, std::string_view test) {
                  auto& list = t.proofs[id];
                  if (std::find(list.begin(), list.end(), test) == list.end()) {
                    list.push_back(test);
                  }
                });
      const std::string reasons = "reasons/" + std::string(table.protocol) + ".tsv";
      ReadTable(table.reasons, reasons.c_str(), t.problems,
                [&](const std::string& where, std::string_view id, std::string_view why) {
                  if (!t.reasons.emplace(id, why).second) {
                    t.problems.push_back(where + ": " + std::string(id) + " has a reason already");
                  }
                });
    }
    return t;
  }();
  return tables;
}

}  // namespace

std::vector<std::string_view> ProofsOf(std::string_view id) {
  const auto& p = Tables().proofs;
  const auto it = p.find(id);
  return it == p.end() ? std::vector<std::string_view>{} : it->second;
}

std::string_view LevelReasonOf(std::string_view id) {
  const auto& r = Tables().reasons;
  const auto it = r.find(id);
  return it == r.end() ? std::string_view{} : it->second;
}

std::vector<std::string> RuleTableProblems() { return Tables().problems; }

bool GlobMatch(std::string_view patterns, std::string_view text) {
  size_t start = 0;
  while (start <= patterns.size()) {
    const size_t comma = patterns.find(',', start);
    const std::string_view one = patterns.substr(
        start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    if (!one.empty() && GlobOne(one, text)) return true;
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return false;
}

std::string RulesMarkdown() {
  size_t must = 0, should = 0, note = 0;
  for (Protocol p : kAllProtocols) {
    for (const Rule& r : RulesFor(p)) {
      (r.level == Level::kMust ? must : r.level == Level::kShould ? should : note)++;
    }
  }
  std::string s;
  s += "# Conformance rules\n\n";
  s += "Generated by `mococheck rules --markdown` from `conformance/rules/`; do not edit\n";
  s += "by hand (a test compares this file with the generated text).\n\n";
  s += "`mococheck run` checks these rules against a device. MUST failures fail the run\n";
  s += "(exit 1); SHOULD failures are reported; NOTE marks a reading the spec leaves\n";
  s += "open and never fails. A rule whose capability the device does not advertise\n";
  s += "when it introduces itself is reported \"not applicable\".\n\n";
  s += "How a level is chosen: MUST where the clause says must (or required), or where a\n";
  s += "host cannot work otherwise; SHOULD where it says should, and for a strong\n";
  s += "reading of the text; NOTE where the spec is silent and real devices differ\n";
  s += "(docs/device-facts.md). A rule is never stricter than the devices the spec allows: the\n";
  s += "levels are checked against the reference firmware's behaviour (the DMC-16's\n";
  s += "`fixtures/profiles/dmc-lite.json`), which fails only where it departs from a\n";
  s += "must or a should.\n\n";
  s += "Every MUST and SHOULD rule is proven able to fail: its \"proven by\" test plants\n";
  s += "a fault and shows the rule failing (conformance/rules/proofs/, checked by CTest\n";
  s += "conformance_rule_proofs). \"Why this level\" reads the level off the clause\n";
  s += "(conformance/rules/reasons/).\n\n";
  s += std::to_string(RuleCount()) + " rules: " + std::to_string(must) + " MUST, " +
       std::to_string(should) + " SHOULD, " + std::to_string(note) + " NOTE.\n";
  for (Protocol p : kAllProtocols) {
    const std::vector<Rule>& rules = RulesFor(p);
    if (rules.empty()) continue;
    size_t pm = 0, ps = 0, pn = 0;
    for (const Rule& r : rules) {
      (r.level == Level::kMust ? pm : r.level == Level::kShould ? ps : pn)++;
    }
    s += "\n## " + std::string(wire::Info(p).title) + " (" + std::to_string(rules.size()) +
         " rules: " + std::to_string(pm) + " MUST, " + std::to_string(ps) + " SHOULD, " +
         std::to_string(pn) + " NOTE)\n\n";
    s +=
        "| id | level | why this level | applies when | rule | spec clause | where | proven by |\n";
    s += "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const Rule& r : rules) {
      const std::string_view why = LevelReasonOf(r.id);
      std::string proofs;
      for (std::string_view t : ProofsOf(r.id)) {
        proofs += (proofs.empty() ? "`" : ", `") + std::string(t) + "`";
      }
      s += "| " + std::string(r.id) + " | " + std::string(LevelName(r.level)) + " | " +
           (why.empty() ? std::string("-") : Escape(why)) + " | " + Escape(r.needs.text) + " | " +
           Escape(r.title) + " | \"" + Escape(r.clause) + "\" | " + Escape(r.source) + " | " +
           (proofs.empty() ? std::string("-") : proofs) + " |\n";
    }
  }
  return s;
}

std::string RulesText() {
  std::string s;
  for (Protocol p : kAllProtocols) {
    for (const Rule& r : RulesFor(p)) {
      std::string id(r.id);
      id.resize(14, ' ');
      std::string level(LevelName(r.level));
      level.resize(7, ' ');
      s += id + level + std::string(r.title);
      const auto proofs = ProofsOf(r.id);
      if (!proofs.empty()) s += " [proof: " + std::string(proofs.front()) + "]";
      s += "\n";
    }
  }
  return s;
}

std::string RulesJson() {
  nlohmann::json out = nlohmann::json::array();
  for (Protocol p : kAllProtocols) {
    for (const Rule& r : RulesFor(p)) {
      nlohmann::json proofs = nlohmann::json::array();
      for (std::string_view t : ProofsOf(r.id)) proofs.push_back(std::string(t));
      out.push_back({{"id", std::string(r.id)},
                     {"protocol", std::string(wire::Info(p).name)},
                     {"level", std::string(LevelName(r.level))},
                     {"needs", std::string(r.needs.text)},
                     {"title", std::string(r.title)},
                     {"clause", std::string(r.clause)},
                     {"source", std::string(r.source)},
                     {"reason", std::string(LevelReasonOf(r.id))},
                     {"proofs", proofs}});
    }
  }
  return out.dump(2) + "\n";
}

}  // namespace moco::conformance
