// Result (result.h): a value or an error, never both.
#include "base/result.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace moco::base {
namespace {

Result<int> Half(int x) {
  if (x % 2 != 0) return std::string("odd: ") + std::to_string(x);
  return x / 2;
}

TEST(Result, HoldsAValue) {
  const Result<int> r = Half(8);
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(static_cast<bool>(r));
  EXPECT_EQ(r.value(), 4);
  EXPECT_EQ(*r, 4);
}

TEST(Result, HoldsAnErrorMessage) {
  const Result<int> r = Half(3);
  ASSERT_FALSE(r.ok());
  EXPECT_FALSE(static_cast<bool>(r));
  EXPECT_EQ(r.error(), "odd: 3");
}

struct Why {
  int code = 0;
};

TEST(Result, CarriesAStructuredErrorAndMovesItsValueOut) {
  Result<std::unique_ptr<int>, Why> r(std::make_unique<int>(7));
  ASSERT_TRUE(r.ok());
  std::unique_ptr<int> p = std::move(r).value();
  EXPECT_EQ(*p, 7);
  const Result<std::string, Why> e(Why{42});
  ASSERT_FALSE(e.ok());
  EXPECT_EQ(e.error().code, 42);
  const Result<std::string, Why> s(std::string("abc"));
  EXPECT_EQ(s->size(), 3u);
}

}  // namespace
}  // namespace moco::base
