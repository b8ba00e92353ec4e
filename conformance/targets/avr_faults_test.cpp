// The simavr target's fault oracles (avr_faults.h) and the ELF symbols they name
// places with (avr_elf.h), on fixtures/firmware/faults_avr/faults.c: each byte
// command shows one fault, and the target stops the firmware with its kind,
// what happened and where.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>

#include <sys/stat.h>

#include "conformance/targets/avr_elf.h"
#include "conformance/targets/simavr_target.h"

namespace moco::conformance {
namespace {

constexpr TimeNs kSecond = 1'000'000'000;

// Boots the fault firmware (its "ok" greeting), sends `command` and runs the
// core for up to a simulated second; the target afterwards.
std::unique_ptr<SimavrTarget> RunCommand(char command, bool watch, std::string* out_text) {
  auto t = std::make_unique<SimavrTarget>(SimavrSpec{MOCO_FAULTS_ELF, "", 0});
  if (watch) {
    EXPECT_TRUE(t->WatchFirmwareFaults());
  }
  EXPECT_EQ(t->Open(), std::nullopt);
  wire::Bytes out;
  while (out.size() < 4 && t->Receive(t->Now() + kSecond, out)) {
  }
  EXPECT_EQ(std::string(out.begin(), out.end()), "ok\r\n");
  const uint8_t byte = static_cast<uint8_t>(command);
  t->Send(wire::ByteView(&byte, 1));
  const TimeNs end = t->Now() + kSecond;
  while (t->Now() < end && t->Receive(end, out)) {
  }
  if (out_text != nullptr) out_text->assign(out.begin() + 4, out.end());
  return t;
}

TEST(AvrSymbols, NameTheFunctionAProgramCounterIsIn) {
  std::string error;
  const AvrSymbols s = AvrSymbols::Read(MOCO_FAULTS_ELF, &error);
  EXPECT_EQ(error, "");
  ASSERT_FALSE(s.empty());
  const auto smash = s.Address("Smash");
  ASSERT_TRUE(smash.has_value());
  ASSERT_NE(s.At(*smash), nullptr);
  EXPECT_EQ(s.At(*smash)->name, "Smash");
  EXPECT_NE(s.Describe(*smash + 4).find("(Smash+0x4)"), std::string::npos)
      << s.Describe(*smash + 4);
  EXPECT_TRUE(s.Address("__udivmodsi4").has_value()) << "libgcc's division is a symbol";
  EXPECT_FALSE(s.Address("NoSuchFunction").has_value());
  // Past the image no function is named.
  EXPECT_EQ(s.Describe(0x7ff0), "0x7ff0");
}

TEST(AvrSymbols, RefuseWhatIsNoAvrElfAndSurviveATruncatedOne) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "avr_elf_test";
  std::filesystem::create_directories(dir);
  std::string error;
  EXPECT_TRUE(AvrSymbols::Read((dir / "missing.elf").string(), &error).empty());
  EXPECT_NE(error.find("too short for an ELF"), std::string::npos) << error;
  std::ofstream((dir / "text.elf").string()) << "not an elf at all, just text\n";
  error.clear();
  EXPECT_TRUE(AvrSymbols::Read((dir / "text.elf").string(), &error).empty());
  EXPECT_NE(error.find("not an ELF file"), std::string::npos) << error;
  // A FIFO would block the reader: refused by what it is, unread, as is a
  // simavr target given one.
  ASSERT_EQ(mkfifo((dir / "fifo.elf").c_str(), 0600), 0);
  error.clear();
  EXPECT_TRUE(AvrSymbols::Read((dir / "fifo.elf").string(), &error).empty());
  EXPECT_NE(error.find("not a regular file"), std::string::npos) << error;
  SimavrTarget fifo(SimavrSpec{(dir / "fifo.elf").string(), "", 0});
  const auto refused_fifo = fifo.Open();
  ASSERT_TRUE(refused_fifo.has_value());
  EXPECT_NE(refused_fifo->find("not a regular file"), std::string::npos) << *refused_fifo;
  // Every cut of a real ELF: no crash; a symbol table cut short is refused.
  std::ifstream in(MOCO_FAULTS_ELF, std::ios::binary);
  const std::string elf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(elf.size(), 1000u);
  size_t refused = 0;
  for (size_t cut = 20; cut < elf.size(); cut += elf.size() / 97) {
    std::ofstream((dir / "cut.elf").string(), std::ios::binary) << elf.substr(0, cut);
    error.clear();
    AvrSymbols::Read((dir / "cut.elf").string(), &error);
    refused += error.empty() ? 0 : 1;
  }
  EXPECT_GT(refused, 90u) << "the section headers come last: most cuts lose them";
  std::filesystem::remove_all(dir);
}

TEST(AvrFaults, AJumpToTheResetVectorIsAResetWhenWatchedAndARebootOtherwise) {
  std::string text;
  auto t = RunCommand('R', true, &text);
  const auto fault = t->FirmwareFaulted();
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->kind, FirmwareFaultKind::kReset);
  EXPECT_NE(fault->what.find("jumped to the reset vector (from 0x"), std::string::npos)
      << fault->what;
  EXPECT_NE(fault->what.find("(main+0x"), std::string::npos) << fault->what;

  auto unwatched = RunCommand('R', false, &text);
  EXPECT_FALSE(unwatched->FirmwareStopped().has_value());
  EXPECT_EQ(text, "ok\r\n") << "unwatched, the firmware starts again and greets";
}

TEST(AvrFaults, AnIllegalInstructionIsACrashEvenUnwatched) {
  for (const bool watch : {true, false}) {
    auto t = RunCommand('I', watch, nullptr);
    const auto fault = t->FirmwareFaulted();
    ASSERT_TRUE(fault.has_value()) << "watch " << watch;
    EXPECT_EQ(fault->kind, FirmwareFaultKind::kCrash);
    EXPECT_NE(fault->what.find("an illegal instruction (0x0001) at 0x"), std::string::npos)
        << fault->what;
  }
}

TEST(AvrFaults, AnOverwrittenReturnAddressIsCaughtAtTheReturnWithABacktrace) {
  auto t = RunCommand('S', true, nullptr);
  const auto fault = t->FirmwareFaulted();
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->kind, FirmwareFaultKind::kStackSmash);
  EXPECT_NE(fault->what.find("a return address was overwritten on the stack: the call at 0x"),
            std::string::npos)
      << fault->what;
  // Caught at the store that did it, before the return (and before the
  // overflow runs on past the end of the data memory).
  EXPECT_NE(fault->what.find("which now holds 0x"), std::string::npos) << fault->what;
  EXPECT_NE(fault->what.find("the instruction at 0x"), std::string::npos) << fault->what;
  EXPECT_NE(fault->what.find("(Smash+0x"), std::string::npos) << fault->what;
  ASSERT_GE(fault->backtrace.size(), 2u);
  EXPECT_NE(fault->backtrace[0].find("(Smash+0x"), std::string::npos) << fault->backtrace[0];
  EXPECT_NE(fault->backtrace[1].find("(main+0x"), std::string::npos) << fault->backtrace[1];
}

TEST(AvrFaults, ADivisionByZeroIsCaughtOnEnteringLibgccsDivision) {
  auto t = RunCommand('D', true, nullptr);
  const auto fault = t->FirmwareFaulted();
  ASSERT_TRUE(fault.has_value());
  EXPECT_EQ(fault->kind, FirmwareFaultKind::kDivisionByZero);
  EXPECT_NE(fault->what.find("__udivmodsi4 entered with a zero divisor, called from 0x"),
            std::string::npos)
      << fault->what;
  EXPECT_NE(fault->what.find("(Divide+0x"), std::string::npos) << fault->what;

  std::string text;
  auto unwatched = RunCommand('D', false, &text);
  EXPECT_FALSE(unwatched->FirmwareStopped().has_value());
  EXPECT_EQ(text, "D") << "unwatched, the division returns and the byte is echoed";
}

// The instruction map marks what ran and which way it went; its summary names
// the functions never entered.
TEST(AvrCodeMap, MarksWhatRanAndNamesTheFunctionsNeverEntered) {
  SimavrTarget t(SimavrSpec{MOCO_FAULTS_ELF, "", 0});
  ASSERT_EQ(t.Open(), std::nullopt);
  std::vector<uint8_t> map(t.InstructionMapBytes());
  ASSERT_GT(map.size(), 100u);
  EXPECT_FALSE(t.SetInstructionMap(map.data(), map.size() - 1)) << "too small a map";
  ASSERT_TRUE(t.SetInstructionMap(map.data(), map.size()));
  auto play = [&](char c) {
    const uint8_t b = static_cast<uint8_t>(c);
    t.Send(wire::ByteView(&b, 1));
    wire::Bytes out;
    const TimeNs end = t.Now() + kSecond / 10;
    while (t.Now() < end && t.Receive(end, out)) {
    }
    return t.CodeCoverageOf(map);
  };
  const auto echo = play('x');
  ASSERT_TRUE(echo.has_value());
  auto never = [](const CodeCoverage& c, const char* f) {
    return std::count(c.never_entered.begin(), c.never_entered.end(), f) == 1;
  };
  EXPECT_TRUE(never(*echo, "Divide"));
  EXPECT_TRUE(never(*echo, "Smash"));
  EXPECT_FALSE(never(*echo, "main"));
  EXPECT_GT(echo->instructions_reached, 10u);
  EXPECT_LT(echo->instructions_reached, echo->instructions);
  // The polling loop's skip both fell through (no byte yet) and skipped.
  EXPECT_GT(echo->edges_reached, echo->instructions_reached);

  const auto divided = play('D');  // unwatched: the division returns
  ASSERT_TRUE(divided.has_value());
  EXPECT_FALSE(never(*divided, "Divide"));
  EXPECT_TRUE(never(*divided, "Smash"));
  EXPECT_GT(divided->instructions_reached, echo->instructions_reached);
  EXPECT_EQ(divided->instructions, echo->instructions);
  EXPECT_EQ(divided->functions, echo->functions);
}

TEST(AvrFaults, OrdinaryTrafficShowsNoFault) {
  std::string text;
  auto t = RunCommand('x', true, &text);
  EXPECT_FALSE(t->FirmwareStopped().has_value()) << *t->FirmwareStopped();
  EXPECT_EQ(text, "x");
  const std::vector<std::string> where = t->FirmwareBacktrace();
  ASSERT_FALSE(where.empty());
  EXPECT_NE(where[0].find("(main+0x"), std::string::npos) << where[0];
}

}  // namespace
}  // namespace moco::conformance
