// `mococheck fuzz` against firmware under simavr (fuzz/executor.h): the
// firmware boots once, each run plays in a process forked from the booted
// state, the program counter's edges are counted into the coverage map, and
// firmware that stops is a finding of its own kind.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "conformance/core/own_dfmoco_pins_testing.h"
#include "conformance/fuzz/campaign.h"
#include "conformance/fuzz/executor.h"
#include "conformance/protocols/dfmoco/dfmoco_protocol.h"
#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

constexpr size_t kMap = size_t{64} << 10;

std::unique_ptr<Target> Firmware(const char* elf) {
  return std::make_unique<SimavrTarget>(SimavrSpec{elf, "", 0});
}

FuzzExecutor::Options Forked() {
  FuzzExecutor::Options o;
  o.fork = true;
  o.coverage_bytes = kMap;
  return o;
}

Messages Lines(std::initializer_list<const char*> lines) {
  Messages out;
  for (const char* l : lines) out.emplace_back(l, l + std::char_traits<char>::length(l));
  return out;
}

std::vector<uint8_t> Copy(std::span<const uint8_t> map) { return {map.begin(), map.end()}; }

size_t Reached(const std::vector<uint8_t>& map) {
  return static_cast<size_t>(std::count_if(map.begin(), map.end(), [](uint8_t c) { return c; }));
}

// A run starts where the boot left the firmware, whatever the run before did:
// the same session reaches the same edges the same number of times.
TEST(SimavrFuzz, EachForkedRunStartsFromTheBootedFirmwareAndCountsItsEdges) {
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(ex.Open(), std::nullopt);
  const Messages greet = Lines({"hi\r\n", "ms\r\n"});
  const Messages move = Lines({"hi\r\n", "pr 1 2000\r\n", "mm 1 400\r\n", "ms\r\n", "mp 1\r\n"});

  FuzzVerdict v = ex.Run(greet);
  ASSERT_TRUE(v.ok) << v.violation;
  const std::vector<uint8_t> first = Copy(ex.coverage());
  ASSERT_EQ(first.size(), kMap);
  EXPECT_GT(Reached(first), 50u) << "the boot's own code is not in a run's map; a run's is";

  v = ex.Run(move);
  ASSERT_TRUE(v.ok) << v.violation;
  const std::vector<uint8_t> moved = Copy(ex.coverage());
  EXPECT_GT(Reached(moved), Reached(first))
      << "a move runs the step and parse code a greeting does not";

  v = ex.Run(greet);
  ASSERT_TRUE(v.ok) << v.violation;
  EXPECT_EQ(Copy(ex.coverage()), first) << "the move's run left a trace in the next";
}

// The campaign keeps a mutant that reached new edges and mutates it further,
// most of them from snapshots after the messages they keep.
TEST(SimavrFuzz, ACampaignOnOurFirmwareGrowsItsCorpusAndFindsNothing) {
  FuzzExecutor::Options snapshots = Forked();
  snapshots.snapshots = 4;
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), snapshots);
  ASSERT_EQ(ex.Open(), std::nullopt);
  Seed seed;
  seed.path = "lines";
  seed.protocol = Protocol::kDfmoco;
  seed.messages = Lines(
      {"hi\r\n", "pr 1 3000\r\n", "mm 1 300\r\n", "ms\r\n", "mp 1\r\n", "zm 1\r\n", "sm 1\r\n"});
  FuzzOptions options;
  options.seed = 7;
  options.runs = 100;
  const FuzzReport r = RunFuzz(ex, Protocol::kDfmoco, {seed}, options);
  EXPECT_EQ(r.execs, 101u);
  EXPECT_GT(r.snapshot_runs, 50u);
  for (const FuzzFailure& f : r.failures) ADD_FAILURE() << f.violation;
  EXPECT_TRUE(r.coverage);
  EXPECT_GT(r.edges, 100u);
  EXPECT_GT(r.corpus, 1u) << "no mutant of 100 reached an edge the seed did not";
  // What the campaign reached of the image, against the ELF's functions.
  ASSERT_TRUE(r.code.has_value());
  EXPECT_GT(r.code->instructions, 500u);
  EXPECT_GT(r.code->instructions_reached, r.code->instructions / 4);
  EXPECT_LT(r.code->instructions_reached, r.code->instructions);
  EXPECT_GT(r.code->edges_reached, r.code->instructions_reached / 2);
  EXPECT_LT(r.code->edges_reached, r.code->edges);
  const std::vector<std::string>& never = r.code->never_entered;
  for (const char* f : {"main", "HandleLine", "SendLine", "StartMove"}) {
    EXPECT_EQ(std::count(never.begin(), never.end(), f), 0) << f;
  }
}

// Firmware that stops (here: it says "bye" and sleeps with interrupts off) is
// a finding of its own kind, named as the target names it; forking from a
// firmware that stops while it boots (before its greeting's line has ended) is
// refused with the reason.
TEST(SimavrFuzz, FirmwareThatStopsIsAFindingOfItsOwnKind) {
  FuzzExecutor::Options here;
  here.coverage_bytes = kMap;
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_HALT_ELF), here);
  ASSERT_EQ(ex.Open(), std::nullopt);
  const FuzzVerdict v = ex.Run(Lines({"hi\r\n"}));
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.kind, FuzzVerdict::Kind::kCrash);
  EXPECT_NE(v.violation.find("the firmware stopped: the core halted"), std::string::npos)
      << v.violation;
  EXPECT_EQ(FindingKindName(v.kind), "crash");

  FuzzExecutor forked(Protocol::kDfmoco, Firmware(MOCO_HALT_ELF), Forked());
  const auto err = forked.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("the firmware stopped while it booted: the core halted"), std::string::npos)
      << *err;
}

// A stack that grows into .data/.bss stops the firmware: the planted bug
// clamps an over-fast pulse rate by recursion, a frame per step/s too many.
// The same session on the firmware without the bug stops nothing.
TEST(SimavrFuzz, AStackOverflowIsFoundAsItsOwnKindWithWhere) {
  const Messages session = Lines({"hi\r\n", "pr 1 30000\r\n", "ms\r\n"});
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_BUG_RECURSIVE_CLAMP_ELF), Forked());
  ASSERT_EQ(ex.Open(), std::nullopt);
  const FuzzVerdict v = ex.Run(session);
  EXPECT_FALSE(v.ok);
  EXPECT_EQ(v.kind, FuzzVerdict::Kind::kStackOverflow);
  EXPECT_NE(v.violation.find("the stack ran into .data/.bss"), std::string::npos) << v.violation;
  EXPECT_NE(v.violation.find("pc 0x"), std::string::npos) << v.violation;
  EXPECT_TRUE(ex.Run(Lines({"hi\r\n", "pr 1 20000\r\n"})).ok) << "a rate within the limit";

  FuzzExecutor good(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(good.Open(), std::nullopt);
  const FuzzVerdict clamped = good.Run(session);
  EXPECT_TRUE(clamped.ok) << clamped.violation;
}

// The planted bugs of fixtures/firmware/dfmoco_avr/dfmoco.c ("Planted bug
// switches"), each with a session that reaches it: each is a finding of the kind
// fixtures/firmware/CMakeLists.txt gives it, where the firmware without the bug
// passes the same session.
struct PlantedBug {
  std::string name, elf, kind;
};

std::vector<PlantedBug> PlantedBugs() {
  std::vector<PlantedBug> out;
  const std::string list = MOCO_DFMOCO_BUGS;
  for (size_t at = 0; at < list.size();) {
    const size_t end = std::min(list.find(',', at), list.size());
    const std::string entry = list.substr(at, end - at);
    const size_t a = entry.find('='), b = entry.rfind('=');
    out.push_back({entry.substr(0, a), entry.substr(a + 1, b - a - 1), entry.substr(b + 1)});
    at = end + 1;
  }
  return out;
}

std::string BugElf(const std::string& name) {
  for (const PlantedBug& b : PlantedBugs()) {
    if (b.name == name) return b.elf;
  }
  ADD_FAILURE() << "no planted bug " << name;
  return "";
}

TEST(SimavrFuzz, EachPlantedBugIsAFindingOfItsKindAndTheGoodFirmwarePasses) {
  const std::map<std::string, std::pair<Messages, std::string>> reach = {
      {"recursive_clamp", {Lines({"hi\r\n", "pr 1 30000\r\n"}), "the stack ran into"}},
      {"args_overflow",
       {Lines({"hi\r\n",
               "mm 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 "
               "26 27 28 29 30 31 32\r\n"}),
        "a return address was overwritten"}},
      {"zero_rate", {Lines({"hi\r\n", "pr 1 0\r\n"}), "__udivmodsi4 entered with a zero"}},
      {"motor_index", {Lines({"hi\r\n", "mm 5 100\r\n"}), "an access outside the data memory"}},
      {"one_reply_slot",
       {Lines({"hi\r\n", "mp 1\r\nmp 2\r\n"}), "every request answered: message 2 (\"mp 1\""}},
      {"hang_stop_all",
       {Lines({"hi\r\n", "pr 1 1000\r\n", "mm 1 20000\r\n", "sa\r\n"}), "hang: the device"}},
  };
  const std::vector<PlantedBug> bugs = PlantedBugs();
  ASSERT_EQ(bugs.size(), reach.size());
  FuzzExecutor good(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(good.Open(), std::nullopt);
  for (const PlantedBug& bug : bugs) {
    SCOPED_TRACE(bug.name);
    ASSERT_TRUE(reach.contains(bug.name)) << "no session reaches the planted bug";
    const auto& [session, what] = reach.at(bug.name);
    FuzzExecutor ex(Protocol::kDfmoco, Firmware(bug.elf.c_str()), Forked());
    ASSERT_EQ(ex.Open(), std::nullopt);
    const FuzzVerdict v = ex.Run(session);
    EXPECT_FALSE(v.ok);
    EXPECT_EQ(FindingKindName(v.kind), bug.kind) << v.violation;
    EXPECT_NE(v.violation.find(what), std::string::npos) << v.violation;
    if (bug.kind != "invariant") {
      ASSERT_FALSE(v.backtrace.empty()) << "a firmware finding says where";
      EXPECT_NE(v.backtrace.front().find(" ("), std::string::npos)
          << "named by the ELF's symbols: " << v.backtrace.front();
    }
    const FuzzVerdict fine = good.Run(session);
    EXPECT_TRUE(fine.ok) << fine.violation;
  }
  // The off-by-one motor check also shows in a reply, where no memory access
  // stops the firmware: a position for a motor the greeting did not announce.
  FuzzExecutor index(Protocol::kDfmoco, Firmware(BugElf("motor_index").c_str()), Forked());
  ASSERT_EQ(index.Open(), std::nullopt);
  const FuzzVerdict reported = index.Run(Lines({"hi\r\n", "mp 5\r\n"}));
  EXPECT_EQ(reported.kind, FuzzVerdict::Kind::kInvariant) << reported.violation;
  EXPECT_NE(reported.violation.find("motor range: \"mp 5 "), std::string::npos)
      << reported.violation;
  EXPECT_TRUE(good.Run(Lines({"hi\r\n", "mp 5\r\n"})).ok)
      << "the good firmware answers parse error";
}

// A saved finding, replayed from a fresh boot without forking, is the fuzzer's
// run again, cycle for cycle: the same violation at the same time and PC, the
// same backtrace; burst writes stay one write each.
TEST(SimavrFuzz, ASavedFindingRerunsCycleForCycle) {
  const Messages session = Lines({"hi\r\n", "pr 1 4000\r\n", "mp 1\r\nmp 2\r\n",
                                  "mm 1 2 3 4 5 6 7 8 9 10 11 12 "
                                  "13 14 15 16 17 18 19 20 21 22 23 24\r\n"});
  const std::string elf = BugElf("args_overflow");
  FuzzExecutor forked(Protocol::kDfmoco, Firmware(elf.c_str()), Forked());
  ASSERT_EQ(forked.Open(), std::nullopt);
  const FuzzVerdict found = forked.Run(session);
  ASSERT_FALSE(found.ok);
  ASSERT_EQ(found.kind, FuzzVerdict::Kind::kStackSmash) << found.violation;

  const std::string path = ::testing::TempDir() + "finding.jsonl";
  ASSERT_EQ(SaveMessages(path, Protocol::kDfmoco, "dfmoco-uno", "a finding", session), "");
  auto loaded = LoadSeed(path, /*as_written=*/true);
  ASSERT_TRUE(std::holds_alternative<Seed>(loaded)) << std::get<std::string>(loaded);
  EXPECT_EQ(std::get<Seed>(loaded).messages, session);
  FuzzExecutor fresh(Protocol::kDfmoco, Firmware(elf.c_str()));
  ASSERT_EQ(fresh.Open(), std::nullopt);
  const FuzzVerdict again = fresh.Run(std::get<Seed>(loaded).messages);
  EXPECT_EQ(again.kind, found.kind);
  EXPECT_EQ(again.violation, found.violation);
  EXPECT_EQ(again.backtrace, found.backtrace);
  std::remove(path.c_str());
}

FuzzExecutor::Options WithSnapshots(size_t kept) {
  FuzzExecutor::Options o = Forked();
  o.snapshots = kept;
  return o;
}

// This process's children (the executor's snapshots and their runs).
std::vector<pid_t> Children() {
  std::vector<pid_t> out;
  std::FILE* f =
      std::fopen(("/proc/self/task/" + std::to_string(getpid()) + "/children").c_str(), "r");
  if (f == nullptr) return out;
  int pid = 0;
  while (std::fscanf(f, "%d", &pid) == 1) out.push_back(pid);
  std::fclose(f);
  return out;
}

// A run from a snapshot after a session's first messages is the whole run's:
// the same finding, word for word and PC for PC, whichever prefix it keeps,
// with two snapshots kept of the four prefixes (older ones given up and made
// again); a smashed run leaves nothing in the snapshot for the next; a run
// from a snapshot twice reaches the same edges; snapshots killed under the
// executor are made again; and none is left once the executor is gone.
TEST(SimavrFuzz, ARunFromASnapshotIsTheWholeRun) {
  const Messages session = Lines({"hi\r\n", "pr 1 4000\r\n", "mp 1\r\nmp 2\r\n",
                                  "mm 1 2 3 4 5 6 7 8 9 10 11 12 "
                                  "13 14 15 16 17 18 19 20 21 22 23 24\r\n"});
  {
    FuzzExecutor ex(Protocol::kDfmoco, Firmware(BugElf("args_overflow").c_str()), WithSnapshots(2));
    ASSERT_EQ(ex.Open(), std::nullopt);
    ASSERT_TRUE(ex.snapshots());
    const FuzzVerdict whole = ex.Run(session);
    ASSERT_FALSE(whole.ok);
    ASSERT_EQ(whole.kind, FuzzVerdict::Kind::kStackSmash) << whole.violation;
    for (size_t kept = 1; kept <= session.size(); ++kept) {
      SCOPED_TRACE("kept " + std::to_string(kept));
      const FuzzVerdict v = ex.Run(session, kept);
      EXPECT_EQ(v.kind, whole.kind);
      EXPECT_EQ(v.violation, whole.violation);
      EXPECT_EQ(v.backtrace, whole.backtrace);
      EXPECT_EQ(v.messages, whole.messages);
      EXPECT_EQ(v.replies, whole.replies);
    }
    EXPECT_LE(Children().size(), 2u) << "more snapshots than kept";

    Messages fine(session.begin(), session.begin() + 3);
    const FuzzVerdict after_smash = ex.Run(fine, 2);
    EXPECT_TRUE(after_smash.ok) << after_smash.violation;
    const std::vector<uint8_t> map = Copy(ex.coverage());
    EXPECT_GT(Reached(map), 20u) << "the rest's edges are in the map";
    EXPECT_TRUE(ex.Run(fine, 2).ok);
    EXPECT_EQ(Copy(ex.coverage()), map) << "the same rest from the same snapshot";

    const std::vector<pid_t> snapshots = Children();
    ASSERT_FALSE(snapshots.empty());
    for (const pid_t pid : snapshots) kill(pid, SIGKILL);
    const FuzzVerdict remade = ex.Run(session, 2);
    EXPECT_EQ(remade.violation, whole.violation);
    EXPECT_TRUE(ex.Run(fine, 2).ok);
  }
  errno = 0;
  EXPECT_EQ(waitpid(-1, nullptr, WNOHANG), -1) << "a snapshot outlived its executor";
  EXPECT_EQ(errno, ECHILD);
}

// A campaign from snapshots finds the over-long line (the session's own
// lines are short), and the finding is shrunk to the bytes that matter: one
// message, shorter than the longest line the mutator makes, that still
// smashes the stack when a fresh boot replays it.
TEST(SimavrFuzz, ASnapshotCampaignFindsAndShrinksAFindingInBytes) {
  const std::string elf = BugElf("args_overflow");
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(elf.c_str()), WithSnapshots(4));
  ASSERT_EQ(ex.Open(), std::nullopt);
  Seed seed;
  seed.path = "lines";
  seed.protocol = Protocol::kDfmoco;
  seed.messages = Lines({"hi\r\n", "pr 1 3000\r\n", "mm 1 300\r\n", "ms\r\n", "mp 1\r\n"});
  FuzzOptions options;
  options.seed = 3;
  options.runs = 400;
  options.max_failures = 1;
  const FuzzReport r = RunFuzz(ex, Protocol::kDfmoco, {seed}, options);
  ASSERT_EQ(r.failures.size(), 1u) << "no finding in 400 runs";
  const FuzzFailure& f = r.failures.front();
  EXPECT_EQ(f.kind, FuzzVerdict::Kind::kStackSmash) << f.violation;
  size_t bytes = 0;
  for (const wire::Bytes& m : f.messages) bytes += m.size();
  EXPECT_LT(bytes, DfmocoProtocol::kMaxFuzzLine) << "not shrunk within the line";

  FuzzExecutor fresh(Protocol::kDfmoco, Firmware(elf.c_str()));
  ASSERT_EQ(fresh.Open(), std::nullopt);
  const FuzzVerdict again = fresh.Run(f.messages);
  EXPECT_EQ(again.kind, f.kind);
  EXPECT_EQ(again.violation, f.violation);
  EXPECT_EQ(again.backtrace, f.backtrace);
}

// With a board, the pin laws judge every run (a pin-law finding naming the
// rule): the golden session itself shows DIR written with the STEP edge
// (DFM-PIN-004, the driver's timing), and a move of 1500 steps asked for its
// position until it has come to rest (under a second) shows the step lost of
// every thousand (DFM-PIN-001, position = pulses), from a snapshot too; the
// firmware without a fault passes both.
TEST(SimavrFuzz, WithABoardThePinLawsAreFindingsOfTheirOwnKind) {
  FuzzExecutor::Options o = WithSnapshots(2);
  o.pins = OwnDfmocoPins();
  auto seed = LoadSeed(std::string(std::getenv("MOCO_SOURCE_DIR") != nullptr
                                       ? std::getenv("MOCO_SOURCE_DIR")
                                       : ".") +
                       "/fixtures/sessions/dfmoco-uno-workflow.jsonl");
  ASSERT_TRUE(std::holds_alternative<Seed>(seed)) << std::get<std::string>(seed);
  const Messages golden = std::get<Seed>(seed).messages;
  Messages long_move = Lines({"hi\r\n", "pr 1 20000\r\n", "mm 1 1500\r\n"});
  for (int i = 0; i < 300; ++i) long_move.push_back(Lines({"mp 1\r\n"}).front());

  FuzzExecutor dir(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_FAULT_DIR_WITH_STEP_ELF), o);
  ASSERT_EQ(dir.Open(), std::nullopt);
  const FuzzVerdict v = dir.Run(golden);
  EXPECT_EQ(v.kind, FuzzVerdict::Kind::kPinLaw) << v.violation;
  EXPECT_EQ(v.violation.rfind("pin law: DFM-PIN-004 ", 0), 0u) << v.violation;
  EXPECT_EQ(FindingKindName(v.kind), "pin-law");

  FuzzExecutor lost(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_FAULT_LOST_STEP_ELF), o);
  ASSERT_EQ(lost.Open(), std::nullopt);
  const FuzzVerdict whole = lost.Run(long_move);
  EXPECT_EQ(whole.kind, FuzzVerdict::Kind::kPinLaw) << whole.violation;
  EXPECT_EQ(whole.violation.rfind("pin law: DFM-PIN-001 ", 0), 0u) << whole.violation;
  const FuzzVerdict from_snapshot = lost.Run(long_move, 3);
  EXPECT_EQ(from_snapshot.violation, whole.violation);
  EXPECT_TRUE(lost.Run(Lines({"hi\r\n", "mp 1\r\n"})).ok) << "under a thousand steps";

  FuzzExecutor good(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), o);
  ASSERT_EQ(good.Open(), std::nullopt);
  for (const Messages* m : {&golden, static_cast<const Messages*>(&long_move)}) {
    const FuzzVerdict fine = good.Run(*m);
    EXPECT_TRUE(fine.ok) << fine.violation;
  }
}

// A pause (an empty message) lets the firmware run 250 ms with nothing sent:
// a move of 1500 steps asked for its position at once is still moving, and
// after four pauses it has come to rest, where the lost step shows
// (DFM-PIN-001). A finding with pauses is saved with them and reruns so.
TEST(SimavrFuzz, APauseLetsAMoveRunItsCourse) {
  FuzzExecutor::Options o = WithSnapshots(2);
  o.pins = OwnDfmocoPins();
  FuzzExecutor lost(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_FAULT_LOST_STEP_ELF), o);
  ASSERT_EQ(lost.Open(), std::nullopt);
  const Messages at_once = Lines({"hi\r\n", "pr 1 20000\r\n", "mm 1 1500\r\n", "mp 1\r\n"});
  const FuzzVerdict moving = lost.Run(at_once);
  EXPECT_TRUE(moving.ok) << moving.violation;
  EXPECT_LT(moving.simulated_ns, 250 * sim::kNsPerMs);

  Messages paused(at_once.begin(), at_once.end() - 1);
  paused.insert(paused.end(), 4, wire::Bytes());
  paused.push_back(at_once.back());
  const FuzzVerdict rest = lost.Run(paused);
  EXPECT_EQ(rest.kind, FuzzVerdict::Kind::kPinLaw) << rest.violation;
  EXPECT_EQ(rest.violation.rfind("pin law: DFM-PIN-001 ", 0), 0u) << rest.violation;
  EXPECT_GE(rest.simulated_ns, 1000 * sim::kNsPerMs);
  EXPECT_EQ(lost.Run(paused, 5).violation, rest.violation) << "from a snapshot after two pauses";

  const std::string path = ::testing::TempDir() + "/paused.jsonl";
  ASSERT_EQ(SaveMessages(path, Protocol::kDfmoco, "dfmoco-uno", "paused", paused), "");
  auto again = LoadSeed(path, /*as_written=*/true);
  ASSERT_TRUE(std::holds_alternative<Seed>(again)) << std::get<std::string>(again);
  EXPECT_EQ(std::get<Seed>(again).messages, paused);
  EXPECT_EQ(lost.Run(std::get<Seed>(again).messages).violation, rest.violation);
  std::remove(path.c_str());

  FuzzExecutor good(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), o);
  ASSERT_EQ(good.Open(), std::nullopt);
  const FuzzVerdict fine = good.Run(paused);
  EXPECT_TRUE(fine.ok) << fine.violation;
}

// The timing mutation finds what only time shows: from a session that asks
// for the position at once, the lost step is found with pauses and not
// without them, in the same runs.
TEST(SimavrFuzz, TheTimingMutationFindsALostStepASessionWithoutPausesCannotShow) {
  Seed seed;
  seed.path = "lines";
  seed.protocol = Protocol::kDfmoco;
  seed.messages = Lines({"hi\r\n", "pr 1 20000\r\n", "mm 1 1500\r\n", "mp 1\r\n"});
  for (const uint32_t percent : {0u, 30u}) {
    FuzzExecutor::Options o = WithSnapshots(4);
    o.pins = OwnDfmocoPins();
    FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_FAULT_LOST_STEP_ELF), o);
    ASSERT_EQ(ex.Open(), std::nullopt);
    FuzzOptions options;
    options.seed = 1;
    options.runs = 300;
    options.max_failures = 1;
    options.pause_percent = percent;
    const FuzzReport r = RunFuzz(ex, Protocol::kDfmoco, {seed}, options);
    if (percent == 0) {
      EXPECT_TRUE(r.failures.empty()) << r.failures.front().violation;
      continue;
    }
    ASSERT_EQ(r.failures.size(), 1u) << "no finding in 300 runs with pauses";
    const FuzzFailure& f = r.failures.front();
    EXPECT_EQ(f.kind, FuzzVerdict::Kind::kPinLaw) << f.violation;
    EXPECT_EQ(f.violation.rfind("pin law: DFM-PIN-001 ", 0), 0u) << f.violation;
    EXPECT_NE(std::ranges::find(f.messages, wire::Bytes()), f.messages.end())
        << "the shrunk finding keeps a pause";
  }
}

// Writes with no answer to wait for queue on the line at 57600 baud: a
// request behind them gets its 100 ms from when it has arrived, not from
// when it was written (four lines of 190 bytes are 130 ms of line time).
TEST(SimavrFuzz, ARequestIsTimedFromItsArrival) {
  FuzzExecutor ex(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), Forked());
  ASSERT_EQ(ex.Open(), std::nullopt);
  std::string flood = "mm 2 -1500";
  while (flood.size() < 190) flood += " 7";
  Messages session;
  for (int i = 0; i < 4; ++i) session.emplace_back(flood.begin(), flood.end());
  for (const wire::Bytes& m : Lines({"\r\n", "mm 1 3000\r\n"})) session.push_back(m);
  const FuzzVerdict v = ex.Run(session);
  EXPECT_TRUE(v.ok) << v.violation;
}

// Fuzzing needs a device in virtual time and coverage a target that sees code.
TEST(SimavrFuzz, AnExecutorRefusesWhatItCannotFuzz) {
  FuzzExecutor::Options o;
  o.coverage_bytes = 1000;
  FuzzExecutor odd(Protocol::kDfmoco, Firmware(MOCO_DFMOCO_ELF), o);
  const auto err = odd.Open();
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("not a power of two"), std::string::npos) << *err;

  FuzzExecutor::Options covered;
  covered.coverage_bytes = kMap;
  FuzzExecutor emulated(Protocol::kDfmoco, InProcessTarget::ForModel("dfmoco", ""), covered);
  const auto no_code = emulated.Open();
  ASSERT_TRUE(no_code.has_value());
  EXPECT_NE(no_code->find("cannot observe its device's code"), std::string::npos) << *no_code;
}

}  // namespace
}  // namespace moco::conformance
