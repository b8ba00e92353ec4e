// Text made safe for XML 1.0 and HTML (JUnit reports, the HTML report, SVG
// plots): markup characters become entities, control characters that XML
// 1.0 does not allow become '?'.
#ifndef MOCO_WIRE_XML_ESCAPE_H_
#define MOCO_WIRE_XML_ESCAPE_H_

#include <string>
#include <string_view>

namespace moco::wire {

// `s` with & < > " ' as &amp; &lt; &gt; &quot; &apos; (safe in text and in
// attributes quoted either way); bytes below 0x20 other than tab, newline and
// carriage return become '?'. Other bytes (UTF-8 included) pass unchanged.
std::string XmlEscape(std::string_view s);

}  // namespace moco::wire

#endif  // MOCO_WIRE_XML_ESCAPE_H_
