// Text made safe for XML 1.0 and HTML (JUnit reports, the HTML report, SVG
// plots): markup characters become entities, control characters that XML
// 1.0 does not allow become '?'.
#ifndef MOCO_BASE_XML_ESCAPE_H_
#define MOCO_BASE_XML_ESCAPE_H_

#include <string>
#include <string_view>

namespace moco::base {

// `s` with & < > " ' as &amp; &lt; &gt; &quot; &apos; (safe in text and in
// attributes quoted either way); bytes below 0x20 other than tab, newline and
// carriage return become '?'. Other bytes (UTF-8 included) pass unchanged.
std::string XmlEscape(std::string_view s);

}  // namespace moco::base

#endif  // MOCO_BASE_XML_ESCAPE_H_
