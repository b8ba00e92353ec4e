// Tests for the step trace probe (ARCHITECTURE "Motion"): bounded ring,
// interval filter, streaming, and agreement with the analytic plan.
#include "sim/step_trace.h"

#include <gtest/gtest.h>

#include <vector>

namespace moco::sim {
namespace {

TEST(StepTraceTest, RingKeepsTheNewestEdgesAndCountsTheRest) {
  Scheduler s;
  StepperMotor m(s, 7);
  StepTrace trace(m, 10);
  m.MoveTo(100);
  s.RunUntilIdle();
  EXPECT_EQ(trace.total(), 100u);
  EXPECT_EQ(trace.size(), 10u);
  EXPECT_EQ(trace.dropped(), 90u);
  const auto edges = trace.Edges();
  ASSERT_EQ(edges.size(), 10u);
  for (size_t i = 0; i < edges.size(); ++i) EXPECT_EQ(edges[i].step, 91 + static_cast<int64_t>(i));
  trace.Clear();
  EXPECT_EQ(trace.size(), 0u);
  EXPECT_TRUE(trace.Edges().empty());
}

TEST(StepTraceTest, IntervalAndStreamSeeTheSameEdgesAsThePlan) {
  Scheduler s;
  StepperMotor m(s, 1);
  m.MoveTo(500);
  const Plan plan = m.CurrentPlan();
  std::vector<StepEdge> analytic;
  plan.ForEachEdge(100 * kNsPerMs, 300 * kNsPerMs,
                   [&](const StepEdge& e) { analytic.push_back(e); });
  ASSERT_FALSE(analytic.empty());
  std::vector<StepEdge> streamed;
  // The probe's interval is closed: [from, to]; ForEachEdge's is (from, to].
  StepTrace trace(m, 0, 100 * kNsPerMs + 1, 300 * kNsPerMs,
                  [&](const StepEdge& e) { streamed.push_back(e); });
  s.RunUntil(200 * kNsPerMs);
  trace.Sync();  // edges up to now, before the move ends
  EXPECT_FALSE(streamed.empty());
  EXPECT_LT(streamed.size(), analytic.size());
  s.RunUntilIdle();
  EXPECT_EQ(streamed, analytic);
  EXPECT_EQ(trace.size(), 0u);  // capacity 0: streaming only
  EXPECT_EQ(trace.total(), analytic.size());
}

TEST(StepTraceTest, ProbeAddedMidMoveSeesEdgesFromThenOn) {
  Scheduler s;
  StepperMotor m(s, 1);
  m.MoveTo(1000);
  s.RunUntil(500 * kNsPerMs);
  const int64_t at = m.Position();
  StepTrace trace(m, 2000);
  s.RunUntilIdle();
  const auto edges = trace.Edges();
  ASSERT_FALSE(edges.empty());
  EXPECT_EQ(edges.front().step, at + 1);
  EXPECT_EQ(edges.back().step, 1000);
}

}  // namespace
}  // namespace moco::sim
