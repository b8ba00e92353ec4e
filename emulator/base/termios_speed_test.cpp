// The one table of line speeds: every named rate maps to its constant and
// back, and a rate the driver cannot set is refused with the rates to use.
#include "base/termios_speed.h"

#include <gtest/gtest.h>

namespace moco::base {
namespace {

TEST(TermiosSpeed, TheRatesDevicesUseMapToTheirConstants) {
  EXPECT_EQ(TermiosSpeed(38400), std::optional<speed_t>(B38400));
  EXPECT_EQ(TermiosSpeed(57600), std::optional<speed_t>(B57600));
  EXPECT_EQ(TermiosSpeed(115200), std::optional<speed_t>(B115200));
  // Rates mococheck's serial: targets did not take before the table was shared.
  EXPECT_EQ(TermiosSpeed(2400), std::optional<speed_t>(B2400));
  EXPECT_EQ(TermiosSpeed(4800), std::optional<speed_t>(B4800));
  EXPECT_EQ(TermiosSpeed(500000), std::optional<speed_t>(B500000));
}

TEST(TermiosSpeed, EveryNamedRateRoundTrips) {
  int named = 0;
  for (uint32_t baud = 1; baud <= 4'000'000; ++baud) {
    const std::optional<speed_t> s = TermiosSpeed(baud);
    if (!s) continue;
    ++named;
    EXPECT_EQ(BaudOfTermiosSpeed(*s), std::optional<uint32_t>(baud)) << baud;
  }
  EXPECT_EQ(named, 30);
}

TEST(TermiosSpeed, RatesTheDriverCannotSetAreRefusedWithTheRatesToUse) {
  for (uint32_t baud : {0u, 14400u, 250000u, 4'000'001u}) {
    EXPECT_FALSE(TermiosSpeed(baud).has_value()) << baud;
  }
  EXPECT_FALSE(BaudOfTermiosSpeed(B0).has_value());
  const std::string hint = NonStandardBaudHint(14400);
  EXPECT_NE(hint.find("14400"), std::string::npos) << hint;
  EXPECT_NE(hint.find("115200"), std::string::npos) << hint;
  EXPECT_NE(hint.find("57600"), std::string::npos) << hint;
}

}  // namespace
}  // namespace moco::base
