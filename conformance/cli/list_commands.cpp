// `mococheck rules` and `mococheck cases`: the rule catalogue (docs/rules.md)
// and the scenario cases of a protocol.
#include <algorithm>
#include <iostream>
#include <memory>

#include "conformance/cli/commands.h"
#include "conformance/protocols/registry.h"

namespace moco::conformance::cli {

Runner AddRulesCommand(CLI::App& app, CLI::App*& sub) {
  auto markdown = std::make_shared<bool>(false);
  auto json = std::make_shared<bool>(false);
  sub = app.add_subcommand("rules",
                           "List the rule catalogue: id, level, what the device must do and the "
                           "test that proves the rule can fail");
  auto* md = sub->add_flag("--markdown", *markdown,
                           "Print docs/rules.md (the catalogue as Markdown, with each rule's "
                           "clause, why its level, and its proving tests)");
  sub->add_flag("--json", *json,
                "Print the catalogue as JSON (id, protocol, level, needs, title, clause, source, "
                "reason, proofs)")
      ->excludes(md);
  return [markdown, json] {
    std::cout << (*json ? RulesJson() : *markdown ? RulesMarkdown() : RulesText());
    return 0;
  };
}

Runner AddCasesCommand(CLI::App& app, CLI::App*& sub) {
  auto protocol = std::make_shared<std::string>("dmc");
  sub = app.add_subcommand("cases", "List the scenario cases (suite/name) and what they need");
  sub->add_option("--protocol", *protocol, wire::NameList(kAllProtocols))->capture_default_str();
  return [protocol] {
    const auto p = wire::ParseProtocolOrAlias(*protocol);
    if (!p) return Fail("--protocol " + *protocol + ": give " + wire::NameList(kAllProtocols));
    const ProtocolRunner* runner = FindRunner(*p);
    if (runner == nullptr) {
      return Fail("no suites for " + std::string(wire::Info(*p).title) + " yet");
    }
    for (const CaseInfo& k : runner->cases()) {
      std::string name = k.suite + "/" + k.name;
      name.resize(std::max<size_t>(name.size() + 2, 26), ' ');
      std::cout << name << k.summary;
      if (!k.needs.empty()) std::cout << " [needs " << k.needs << "]";
      std::cout << "\n";
    }
    return 0;
  };
}

}  // namespace moco::conformance::cli
