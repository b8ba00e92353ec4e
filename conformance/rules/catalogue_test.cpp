// The DMC v2 rule catalogue: well-formed ids and clauses, glob selection, and
// docs/rules.md equal to the generated text.
#include "conformance/rules/catalogue.h"

#include "conformance/protocols/dmc/dmc_protocol.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <set>
#include <span>
#include <sstream>
#include <string_view>

namespace moco::conformance {
namespace {

TEST(Catalogue, IdsAreUniqueWellFormedAndEveryRuleQuotesItsClause) {
  std::set<std::string> ids;
  // "DMC-" FAMILY "-" three digits.
  const auto shape = [](std::string_view id) {
    if (id.rfind("DMC-", 0) != 0 || id.size() < 9) return false;
    const size_t dash = id.rfind('-');
    if (dash <= 4 || id.size() - dash != 4) return false;
    for (size_t i = 4; i < dash; ++i) {
      if (id[i] < 'A' || id[i] > 'Z') return false;
    }
    for (size_t i = dash + 1; i < id.size(); ++i) {
      if (id[i] < '0' || id[i] > '9') return false;
    }
    return true;
  };
  for (const Rule& r : DmcRules()) {
    EXPECT_TRUE(shape(r.id)) << r.id;
    EXPECT_TRUE(ids.insert(std::string(r.id)).second) << "duplicate " << r.id;
    EXPECT_FALSE(r.title.empty()) << r.id;
    EXPECT_GE(r.clause.size(), 10u) << r.id << " quotes no clause";
    EXPECT_FALSE(r.source.empty()) << r.id;
    EXPECT_EQ(FindRule(r.id), &r);
  }
  EXPECT_GE(DmcRules().size(), 60u);
  EXPECT_EQ(FindRule("DMC-NOPE-001"), nullptr);
}

TEST(Catalogue, RulesTheBriefNamesArePresentWithTheirLevels) {
  for (const char* id : {"DMC-FRAME-001", "DMC-CSUM-001", "DMC-ACK-003", "DMC-HI-002",
                         "DMC-POS-001", "DMC-RT-004"}) {
    const Rule* r = FindRule(id);
    ASSERT_NE(r, nullptr) << id;
    EXPECT_EQ(r->level, Level::kMust) << id;
  }
  EXPECT_EQ(FindRule("DMC-HI-003")->level, Level::kNote);     // the 49-byte HI (FACTS)
  EXPECT_EQ(FindRule("DMC-HI-011")->level, Level::kShould);   // "should issue a MSG_HI"
  EXPECT_EQ(FindRule("DMC-POS-002")->level, Level::kShould);  // "about every 0.10 seconds"
}

TEST(Catalogue, ApplicabilityFollowsTheHiDescription) {
  dmc::HiResponse bare;  // no motors, no capabilities
  EXPECT_TRUE(Applies(*FindRule("DMC-CSUM-001"), bare));
  EXPECT_FALSE(Applies(*FindRule("DMC-MOVE-003"), bare));
  EXPECT_FALSE(Applies(*FindRule("DMC-RT-004"), bare));
  dmc::HiResponse rt = bare;
  rt.motor_count = 2;
  rt.capabilities = dmc::kCapRealTime;
  EXPECT_TRUE(Applies(*FindRule("DMC-RT-004"), rt));
  EXPECT_FALSE(Applies(*FindRule("DMC-GM-001"), rt));
  EXPECT_TRUE(Applies(*FindRule("DMC-ERR-010"), rt));
  // The real-time outputs: DMX channels, GIO outputs, the camera capability.
  EXPECT_FALSE(Applies(*FindRule("DMC-DMX-005"), rt));
  EXPECT_FALSE(Applies(*FindRule("DMC-RT-017"), rt));
  EXPECT_FALSE(Applies(*FindRule("DMC-RT-021"), rt));
  EXPECT_TRUE(Applies(*FindRule("DMC-RT-026"), rt));
  dmc::HiResponse io = rt;
  io.dmx_count = 4;
  io.gio_out_count = 1;
  io.capabilities |= dmc::kCapRtCameraTrigger;
  EXPECT_TRUE(Applies(*FindRule("DMC-DMX-005"), io));
  EXPECT_TRUE(Applies(*FindRule("DMC-RT-017"), io));
  EXPECT_TRUE(Applies(*FindRule("DMC-RT-021"), io));
  io.capabilities &= ~dmc::kCapRealTime;
  EXPECT_FALSE(Applies(*FindRule("DMC-DMX-005"), io));
  EXPECT_FALSE(Applies(*FindRule("DMC-RT-021"), io));
  rt.capabilities |= dmc::kCapVirtXyz;
  EXPECT_FALSE(Applies(*FindRule("DMC-ERR-010"), rt));
  EXPECT_TRUE(Applies(*FindRule("DMC-VIRT-001"), rt));
}

TEST(Catalogue, GlobMatchesStarsQuestionMarksAndAlternatives) {
  EXPECT_TRUE(GlobMatch("DMC-HI-*", "DMC-HI-002"));
  EXPECT_FALSE(GlobMatch("DMC-HI-*", "DMC-HARD-002"));
  EXPECT_TRUE(GlobMatch("DMC-ACK-00?", "DMC-ACK-003"));
  EXPECT_FALSE(GlobMatch("DMC-ACK-00?", "DMC-ACK-010"));
  EXPECT_TRUE(GlobMatch("DMC-RT-*,DMC-CSUM-001", "DMC-CSUM-001"));
  EXPECT_TRUE(GlobMatch("*", "anything"));
  EXPECT_TRUE(GlobMatch("motor/*", "motor/move"));
  EXPECT_FALSE(GlobMatch("", "DMC-HI-001"));
  EXPECT_FALSE(GlobMatch("DMC-HI-001", "DMC-HI-0011"));
}

TEST(Catalogue, DocsRulesMdIsTheGeneratedCatalogue) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string path = std::string(root != nullptr ? root : ".") + "/docs/rules.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << "cannot read " << path;
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(), RulesMarkdown())
      << "docs/rules.md is stale: regenerate it with `mococheck rules --markdown > docs/rules.md`";
}

// A rule that cites docs/device-facts.md can be looked up there: the section
// it names is on the page, and when the page is its only source, every
// fragment of its clause (between "..." and " / ") is on the page (when it is
// one of several, the clause quotes the vendor specification).
TEST(Catalogue, RulesCitingTheDeviceFactsQuoteThem) {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string path = std::string(root != nullptr ? root : ".") + "/docs/device-facts.md";
  std::ifstream in(path);
  ASSERT_TRUE(in) << "cannot read " << path;
  std::stringstream text;
  text << in.rdbuf();
  // Whitespace runs as one space: the page wraps its lines.
  const auto squeeze = [](std::string_view t) {
    std::string out;
    for (const char c : t) {
      const bool space = c == ' ' || c == '\n' || c == '\t';
      if (space && (out.empty() || out.back() == ' ')) continue;
      out += space ? ' ' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    }
    return out;
  };
  const std::string page = squeeze(text.str());
  size_t citing = 0;
  for (const Protocol p : kAllProtocols) {
    for (const Rule& r : RulesFor(p)) {
      if (r.source.find("docs/device-facts.md") == std::string_view::npos) continue;
      ++citing;
      EXPECT_EQ(r.source.find("FACTS"), std::string_view::npos) << r.id;
      std::vector<std::string> fragments;
      std::string clause(r.clause);
      for (const std::string_view sep : {"...", " / "}) {
        for (size_t at; (at = clause.find(sep)) != std::string::npos;) {
          clause.replace(at, sep.size(), "\x01");
        }
      }
      std::stringstream parts(clause);
      for (std::string f; std::getline(parts, f, '\x01');) {
        f = squeeze(f);
        while (!f.empty() && f.front() == ' ') f.erase(f.begin());
        while (!f.empty() && (f.back() == ' ' || f.back() == '.')) f.pop_back();
        if (f.size() >= 3) fragments.push_back(f);
      }
      // "docs/device-facts.md, DMC v2 (...)": the page has a section "## DMC v2...".
      std::string section(r.source.substr(r.source.find("docs/device-facts.md")));
      section = section.substr(std::min(section.size(), section.find(", ") + 2));
      section = section.substr(0, std::min(section.find(" ("), section.find(';')));
      EXPECT_NE(page.find("## " + squeeze(section)), std::string::npos)
          << r.id << ": no section \"" << section << "\" on " << path;
      if (r.source.find(';') == std::string_view::npos) {
        for (const std::string& f : fragments) {
          EXPECT_NE(page.find(f), std::string::npos)
              << r.id << ": \"" << f << "\" of its clause is not on " << path;
        }
      }
    }
  }
  EXPECT_GT(citing, 40u);
}

TEST(Catalogue, MarkdownCountsLevels) {
  size_t must = 0;
  for (const Rule& r : DmcRules()) must += r.level == Level::kMust;
  EXPECT_NE(RulesMarkdown().find(std::to_string(must) + " MUST"), std::string::npos);
}

// The proving-test and level-reason tables name only rules that exist, in
// well-formed lines, one reason per rule.
TEST(Catalogue, RuleTablesNameOnlyRulesThatExist) {
  const std::vector<std::string> problems = RuleTableProblems();
  EXPECT_TRUE(problems.empty()) << problems.size() << " problem(s), first: "
                                << (problems.empty() ? "" : problems.front());
}

// One pair of tables per protocol with rules, named as the protocol is, and
// none for a protocol without rules.
TEST(Catalogue, EveryProtocolWithRulesHasItsProofAndReasonTables) {
  std::set<std::string_view> tables;
  for (const detail::RuleTableText& t : detail::RuleTableTexts()) {
    EXPECT_TRUE(tables.insert(t.protocol).second) << t.protocol;
    EXPECT_FALSE(t.proofs.empty()) << t.protocol;
    EXPECT_FALSE(t.reasons.empty()) << t.protocol;
  }
  std::set<std::string_view> with_rules;
  for (Protocol p : kAllProtocols) with_rules.insert(ProtocolName(p));
  EXPECT_EQ(tables, with_rules);
}

// Every rule says why it has its level (conformance/rules/reasons/*.tsv), and
// the reason opens with the level's word, so a level changed later without its
// reason fails here instead of showing a reason that argues for another level.
TEST(Catalogue, EveryRuleSaysWhyItHasItsLevel) {
  size_t checked = 0;
  for (Protocol p : kAllProtocols) {
    for (const Rule& r : RulesFor(p)) {
      ++checked;
      const std::string_view why = LevelReasonOf(r.id);
      const std::string word = std::string(LevelName(r.level)) + ":";
      if (why.empty()) {
        ADD_FAILURE() << r.id << " has no reason in conformance/rules/reasons/" << ProtocolName(p)
                      << ".tsv";
        continue;
      }
      EXPECT_EQ(why.substr(0, word.size()), word)
          << r.id << " is " << LevelName(r.level) << " but its reason says: " << why;
      EXPECT_GT(why.size(), word.size() + 20) << r.id << " gives no reason after " << word;
    }
  }
  EXPECT_EQ(checked, RuleCount());
  EXPECT_GE(checked, 200u);
}

TEST(Catalogue, ProvingTestsAreShownByTheCatalogue) {
  const std::string json = RulesJson();
  for (const Rule& r : DmcRules()) {
    for (std::string_view t : ProofsOf(r.id)) {
      EXPECT_NE(RulesMarkdown().find("`" + std::string(t) + "`"), std::string::npos) << t;
      EXPECT_NE(json.find("\"" + std::string(t) + "\""), std::string::npos) << t;
    }
  }
  EXPECT_FALSE(ProofsOf("DMC-CSUM-001").empty()) << "the corrupted-checksum test proves it";
}

// Each protocol declares its own needs (rules/<p>_needs.h) beside the shared
// ones (rules/needs.h): every need has an id no other need has, named after
// its protocol, and a text the catalogue and the reports print, which no
// other need reads alike (so a text names one need).
TEST(Catalogue, EachProtocolsNeedsHaveDistinctIdsAndText) {
  std::set<std::string_view> ids, texts;
  for (const Need& n : SharedNeeds::kShared) {
    EXPECT_FALSE(n.id.empty());
    EXPECT_FALSE(n.text.empty()) << n.id;
    EXPECT_TRUE(ids.insert(n.id).second) << "two needs are " << n.id;
    EXPECT_TRUE(texts.insert(n.text).second) << "two needs read " << n.text;
  }
  for (const RuleSet& set : kRuleSets) {
    const std::string prefix = std::string(ProtocolName(set.protocol)) + ".";
    EXPECT_FALSE(set.needs.empty()) << ProtocolName(set.protocol);
    for (const Need& n : set.needs) {
      EXPECT_TRUE(n.id.starts_with(prefix)) << n.id << " is a need of " << prefix;
      EXPECT_GT(n.id.size(), prefix.size()) << n.id;
      EXPECT_FALSE(n.text.empty()) << n.id;
      EXPECT_TRUE(ids.insert(n.id).second) << "two needs are " << n.id;
      EXPECT_TRUE(texts.insert(n.text).second) << "two needs read " << n.text;
    }
  }
}

// A rule needs what its own protocol declares or what every protocol shares,
// never another protocol's need (which that protocol's traits would never meet).
TEST(Catalogue, EveryRuleNeedsOnlyItsOwnProtocolsOrSharedNeeds) {
  const auto holds = [](std::span<const Need> needs, const Need& need) {
    return std::any_of(needs.begin(), needs.end(),
                       [&](const Need& n) { return n.id == need.id && n.text == need.text; });
  };
  size_t checked = 0;
  for (const RuleSet& set : kRuleSets) {
    for (const Rule& r : set.rules()) {
      ++checked;
      EXPECT_TRUE(holds(set.needs, r.needs) || holds(SharedNeeds::kShared, r.needs))
          << r.id << " needs " << r.needs.id << ", which " << ProtocolName(set.protocol)
          << " does not declare";
    }
  }
  EXPECT_EQ(checked, RuleCount());
}

}  // namespace
}  // namespace moco::conformance
