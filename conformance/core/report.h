// mococheck reports: console text, JSON, JUnit XML (one testcase per rule
// and scenario case) and HTML, each file written atomically.
#ifndef MOCO_CONFORMANCE_CORE_REPORT_H_
#define MOCO_CONFORMANCE_CORE_REPORT_H_

#include <string>

#include <nlohmann/json.hpp>

#include "base/xml_escape.h"
#include "conformance/core/run_report.h"

namespace moco::conformance {

// Per case and failing rule with its evidence, then the rule summary.
// `verbose` also lists the rules that passed in each case.
std::string ConsoleReport(const RunReport& report, bool verbose);
// The same in the pieces mococheck streams as the run goes on:
// ConsoleTitle() before the run, ConsoleDevice() once the device introduced
// itself, ConsoleCase() per finished case, ConsoleSummary() at the end.
std::string ConsoleTitle(const std::string& target, const std::string& protocol_name);
std::string ConsoleDevice(const RunReport& report);
std::string ConsoleCase(const CaseResult& c, bool verbose);
std::string ConsoleSummary(const RunReport& report, bool verbose);
nlohmann::json JsonReport(const RunReport& report);
std::string JunitReport(const RunReport& report);
// A self-contained HTML page (html_report.cpp): verdict, rule table, per case
// the failing rules with clause, evidence and the transcript around each
// failure, and a plot of reported motor positions.
std::string HtmlReport(const RunReport& report);

// XML/HTML escaping for the reports (base/xml_escape.h).
using base::XmlEscape;

// Writes `text` as the whole file at `path` (base::WriteFileAtomically: a
// regular file is replaced atomically, a device or FIFO such as /dev/null is
// written in place, a directory is refused). Returns an error message, or an
// empty string.
std::string WriteAtomically(const std::string& path, const std::string& text);

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_REPORT_H_
