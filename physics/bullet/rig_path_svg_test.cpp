// Tests of the head-path plot (docs/rig-dynamics.md "Plots"): a well-formed
// SVG document (checked by a small XML reader here) with both paths per view
// and labelled axes, for any samples.
#include "physics/bullet/rig_path_svg.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace moco::physics {
namespace {

// A small XML well-formedness check: one root element, tags balanced and
// properly nested, attributes quoted, '<' never in text, entities known.
// Returns "" when well-formed, otherwise what is wrong.
std::string XmlProblem(const std::string& doc) {
  std::vector<std::string> open;
  size_t roots = 0;
  size_t i = 0;
  auto entity_ok = [&](size_t amp) {
    for (const char* e : {"&amp;", "&lt;", "&gt;", "&quot;", "&apos;"}) {
      if (doc.compare(amp, std::char_traits<char>::length(e), e) == 0) return true;
    }
    return false;
  };
  while (i < doc.size()) {
    if (doc[i] != '<') {
      if (doc[i] == '&' && !entity_ok(i)) return "bad entity at " + std::to_string(i);
      if (open.empty() && !std::isspace(static_cast<unsigned char>(doc[i]))) {
        return "text outside the root at " + std::to_string(i);
      }
      ++i;
      continue;
    }
    if (doc.compare(i, 5, "<?xml") == 0) {
      if (i != 0) return "XML declaration not first";
      const size_t end = doc.find("?>", i);
      if (end == std::string::npos) return "unterminated declaration";
      i = end + 2;
      continue;
    }
    if (doc.compare(i, 4, "<!--") == 0) {
      const size_t end = doc.find("-->", i);
      if (end == std::string::npos) return "unterminated comment";
      i = end + 3;
      continue;
    }
    const bool closing = i + 1 < doc.size() && doc[i + 1] == '/';
    size_t j = i + (closing ? 2 : 1);
    const size_t name_start = j;
    while (j < doc.size() && (std::isalnum(static_cast<unsigned char>(doc[j])) || doc[j] == '-' ||
                              doc[j] == ':' || doc[j] == '_')) {
      ++j;
    }
    const std::string name = doc.substr(name_start, j - name_start);
    if (name.empty()) return "tag without a name at " + std::to_string(i);
    // Attributes: name="value" pairs; values hold no '<' and no raw '"'.
    bool self_closing = false;
    while (true) {
      while (j < doc.size() && std::isspace(static_cast<unsigned char>(doc[j]))) ++j;
      if (j >= doc.size()) return "unterminated tag " + name;
      if (doc[j] == '>') {
        ++j;
        break;
      }
      if (doc.compare(j, 2, "/>") == 0 && !closing) {
        self_closing = true;
        j += 2;
        break;
      }
      if (closing) return "attributes on a closing tag " + name;
      const size_t attr_start = j;
      while (j < doc.size() && doc[j] != '=' && !std::isspace(static_cast<unsigned char>(doc[j])) &&
             doc[j] != '>') {
        ++j;
      }
      if (j == attr_start || j >= doc.size() || doc[j] != '=') return "bad attribute in " + name;
      ++j;
      if (j >= doc.size() || doc[j] != '"') return "unquoted attribute in " + name;
      const size_t end = doc.find('"', j + 1);
      if (end == std::string::npos) return "unterminated attribute in " + name;
      for (size_t k = j + 1; k < end; ++k) {
        if (doc[k] == '<') return "'<' in an attribute of " + name;
        if (doc[k] == '&' && !entity_ok(k)) return "bad entity in an attribute of " + name;
      }
      j = end + 1;
    }
    if (closing) {
      if (open.empty() || open.back() != name) return "unbalanced </" + name + ">";
      open.pop_back();
    } else {
      if (open.empty()) ++roots;
      if (!self_closing) open.push_back(name);
    }
    i = j;
  }
  if (!open.empty()) return "unclosed <" + open.back() + ">";
  if (roots != 1) return "expected one root element, found " + std::to_string(roots);
  return "";
}

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::vector<RigPathSample> Circle(int n) {
  std::vector<RigPathSample> samples;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * 3.141592653589793 * i / n;
    samples.push_back({i * 1e-3,
                       {std::cos(a), 1 + std::sin(a), 0.2 * a},
                       {std::cos(a) - 0.01, 1 + std::sin(a), 0.2 * a - 0.005}});
  }
  return samples;
}

TEST(XmlProblemTest, TheCheckerRejectsWhatIsNotWellFormed) {
  EXPECT_EQ(XmlProblem("<a><b/></a>"), "");
  EXPECT_NE(XmlProblem("<a><b></a>"), "");
  EXPECT_NE(XmlProblem("<a></a><a></a>"), "");
  EXPECT_NE(XmlProblem("<a x=1></a>"), "");
  EXPECT_NE(XmlProblem("<a>1 < 2</a>"), "");
  EXPECT_NE(XmlProblem("<a>&nbsp;</a>"), "");
  EXPECT_NE(XmlProblem("<a>"), "");
}

TEST(RigPathSvgTest, IsWellFormedWithBothPathsInBothViewsAndAxisLabels) {
  const std::string svg = RigPathSvg(Circle(500), "circle & drift <test>");
  EXPECT_EQ(XmlProblem(svg), "");
  EXPECT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_EQ(Count(svg, "<svg xmlns=\"http://www.w3.org/2000/svg\""), 1u);
  for (const char* id : {"top-commanded", "top-physical", "side-commanded", "side-physical"}) {
    const std::string attr = std::string("id=\"") + id + "\" d=\"M";
    EXPECT_EQ(Count(svg, attr), 1u) << id;
  }
  // 500 points: one M and 499 L per path.
  const size_t start = svg.find("id=\"top-physical\"");
  const size_t end = svg.find("/>", start);
  EXPECT_EQ(Count(svg.substr(start, end - start), " L"), 499u);
  EXPECT_NE(svg.find("x, east-west [m]"), std::string::npos);
  EXPECT_NE(svg.find("y, along the track [m]"), std::string::npos);
  EXPECT_NE(svg.find("z, up [m]"), std::string::npos);
  EXPECT_NE(svg.find("top view"), std::string::npos);
  EXPECT_NE(svg.find("side view"), std::string::npos);
  EXPECT_NE(svg.find("circle &amp; drift &lt;test&gt;"), std::string::npos);
  EXPECT_EQ(svg.find("<test>"), std::string::npos);
}

TEST(RigPathSvgTest, LongPathsAreThinnedAndEndOnTheLastPoint) {
  const std::vector<RigPathSample> samples = Circle(20000);
  const std::string svg = RigPathSvg(samples);
  EXPECT_EQ(XmlProblem(svg), "");
  const size_t start = svg.find("id=\"side-commanded\"");
  const std::string path = svg.substr(start, svg.find("/>", start) - start);
  EXPECT_LE(Count(path, " L"), 2000u);
  EXPECT_GE(Count(path, " L"), 1000u);
}

TEST(RigPathSvgTest, NoSamplesStillGiveADocument) {
  const std::string svg = RigPathSvg({});
  EXPECT_EQ(XmlProblem(svg), "");
  EXPECT_NE(svg.find("id=\"top-physical\""), std::string::npos);
}

// Any samples (NaN and infinities included) and any title give a
// well-formed document.
RC_GTEST_PROP(RigPathSvgProperty, AnyInputIsWellFormed,
              (const std::vector<std::array<double, 7>>& raw, const std::string& title)) {
  std::vector<RigPathSample> samples;
  for (const auto& r : raw) {
    samples.push_back({r[0], {r[1], r[2], r[3]}, {r[4], r[5], r[6]}});
  }
  if (*rc::gen::arbitrary<bool>() && !samples.empty()) {
    samples[0].physical_m[1] = std::numeric_limits<double>::quiet_NaN();
    samples.back().commanded_m[2] = std::numeric_limits<double>::infinity();
  }
  const std::string svg = RigPathSvg(samples, title);
  RC_ASSERT(XmlProblem(svg) == "");
}

}  // namespace
}  // namespace moco::physics
