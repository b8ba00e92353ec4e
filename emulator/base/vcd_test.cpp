// Value Change Dump text: header, $dumpvars and merged changes (IEEE 1364 section 18).
#include "base/vcd.h"

#include <gtest/gtest.h>

namespace moco::base {
namespace {

TEST(Vcd, ChangesOfEveryWireAreMergedInTimeOrderUnderOneTimestamp) {
  std::vector<VcdWire> wires = {{"m1_step", false, {{100, true}, {125, false}}},
                                {"m1_dir", true, {{100, false}}}};
  const std::string text = VcdText("board", "case motor/move", wires);
  EXPECT_NE(text.find("$timescale 1 ns $end"), std::string::npos);
  EXPECT_NE(text.find("$var wire 1 ! m1_step $end"), std::string::npos);
  EXPECT_NE(text.find("$var wire 1 \" m1_dir $end"), std::string::npos);
  EXPECT_NE(text.find("$dumpvars\n0!\n1\"\n$end\n#100\n1!\n0\"\n#125\n0!\n"), std::string::npos)
      << text;
}

TEST(Vcd, RepeatedLevelsAreNotChanges) {
  std::vector<VcdWire> wires = {{"a", false, {{5, false}, {7, true}, {9, true}}}};
  const std::string text = VcdText("s", "", wires);
  EXPECT_EQ(text.find("#5"), std::string::npos);
  EXPECT_NE(text.find("#7\n1!\n"), std::string::npos);
  EXPECT_EQ(text.find("#9"), std::string::npos);
}

TEST(Vcd, IdentifiersStayUniqueBeyondOneCharacter) {
  EXPECT_EQ(VcdIdentifier(0), "!");
  EXPECT_EQ(VcdIdentifier(93), "~");
  EXPECT_EQ(VcdIdentifier(94), "!\"");
  EXPECT_NE(VcdIdentifier(95), VcdIdentifier(94));
}

TEST(Vcd, NamesAndCommentsCannotBreakTheSyntax) {
  std::vector<VcdWire> wires = {{"bad name$", false, {}}};
  const std::string text = VcdText("my scope", "a $end b", wires);
  EXPECT_NE(text.find("$var wire 1 ! bad_name_ $end"), std::string::npos);
  EXPECT_NE(text.find("$scope module my_scope $end"), std::string::npos);
  EXPECT_NE(text.find("$comment a _end b $end"), std::string::npos);
}

}  // namespace
}  // namespace moco::base
