// XmlEscape (xml_escape.h): entities for markup, '?' for the control
// characters XML 1.0 forbids, everything else unchanged.
#include "base/xml_escape.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <string>

namespace moco::base {
namespace {

TEST(XmlEscape, MarkupBecomesEntities) {
  EXPECT_EQ(XmlEscape(R"(a<b>&"c"'d')"), "a&lt;b&gt;&amp;&quot;c&quot;&apos;d&apos;");
  EXPECT_EQ(XmlEscape("&amp;"), "&amp;amp;");  // not recognised as an entity: escaped again
}

TEST(XmlEscape, ForbiddenControlCharactersBecomeAQuestionMark) {
  EXPECT_EQ(XmlEscape(std::string("a\0b\x01\x1f", 5)), "a?b??");
  EXPECT_EQ(XmlEscape("tab\tline\ncr\r"), "tab\tline\ncr\r");
  EXPECT_EQ(XmlEscape("caf\xc3\xa9 \x7f"), "caf\xc3\xa9 \x7f");
}

// Whatever the input, the output holds no markup character outside an
// entity and no forbidden control character, and unescaping gives the input
// back with the forbidden characters as '?'.
RC_GTEST_PROP(XmlEscape, OutputIsSafeAndUnescapesToTheInput, (const std::string& s)) {
  const std::string out = XmlEscape(s);
  std::string back;
  for (size_t i = 0; i < out.size(); ++i) {
    const char c = out[i];
    RC_ASSERT(c != '<');
    RC_ASSERT(c != '>');
    RC_ASSERT(c != '"');
    RC_ASSERT(c != '\'');
    RC_ASSERT(!(static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r'));
    if (c != '&') {
      back += c;
      continue;
    }
    const size_t semi = out.find(';', i);
    RC_ASSERT(semi != std::string::npos);
    const std::string entity = out.substr(i, semi - i + 1);
    if (entity == "&amp;")
      back += '&';
    else if (entity == "&lt;")
      back += '<';
    else if (entity == "&gt;")
      back += '>';
    else if (entity == "&quot;")
      back += '"';
    else if (entity == "&apos;")
      back += '\'';
    else
      RC_FAIL("unknown entity " + entity);
    i = semi;
  }
  std::string expected = s;
  for (char& c : expected) {
    if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') c = '?';
  }
  RC_ASSERT(back == expected);
}

}  // namespace
}  // namespace moco::base
