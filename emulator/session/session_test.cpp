// Tests for the session file format of docs/sessions.md: parsing, errors that
// name the line and the fix, the write-then-rename rule, and round trips.
#include "session/session.h"

#include <gtest/gtest.h>
#include <rapidcheck/gtest.h>

#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

namespace moco::session {
namespace {

Session Ok(std::variant<Session, SessionError> r) {
  if (const auto* e = std::get_if<SessionError>(&r)) {
    ADD_FAILURE() << "line " << e->line << ": " << e->message;
    return {};
  }
  return std::get<Session>(std::move(r));
}

TEST(SessionTest, ParsesHeaderTrafficAndEvents) {
  const char* text =
      "{\"mocosim_session\":1,\"protocol\":\"dmc\",\"device\":\"dmc16\",\"clock\":\"virtual\","
      "\"tolerances\":{\"position_steps\":2,\"time_ms\":20},\"vendor_field\":7}\n"
      "{\"t_ns\":0,\"from\":\"host\",\"hex\":\"4446\"}\n"
      "\n"
      "{\"t_ns\":5,\"from\":\"device\",\"hex\":\"AB cd\",\"decoded\":[\"X\"]}\n"
      "{\"t_ns\":9,\"event\":\"estop\",\"state\":\"pressed\"}";
  const Session s = Ok(ParseSession(text));
  EXPECT_EQ(s.header.protocol, Protocol::kDmc);
  EXPECT_EQ(s.header.device, "dmc16");
  EXPECT_EQ(s.header.tolerance_position_steps, 2);
  EXPECT_EQ(s.header.tolerance_time_ms, 20);
  EXPECT_EQ(s.header.extra["vendor_field"], 7);
  ASSERT_EQ(s.entries.size(), 3u);
  EXPECT_EQ(s.entries[0].from, Origin::kHost);
  EXPECT_EQ(s.entries[0].bytes, (wire::Bytes{0x44, 0x46}));
  EXPECT_EQ(s.entries[1].from, Origin::kDevice);
  EXPECT_EQ(s.entries[1].bytes, (wire::Bytes{0xab, 0xcd}));
  EXPECT_EQ(s.entries[1].decoded, std::vector<std::string>{"X"});
  EXPECT_TRUE(s.entries[2].is_event);
  EXPECT_EQ(s.entries[2].event["state"], "pressed");
}

struct BadCase {
  const char* text;
  size_t line;
  const char* needle;
};

TEST(SessionTest, ErrorsNameTheLineAndTheFix) {
  const BadCase cases[] = {
      {"", 1, "header"},
      {"{\"protocol\":\"dmc\"}", 1, "mocosim_session"},
      {"{\"mocosim_session\":2,\"protocol\":\"dmc\"}", 1, "upgrade"},
      {"{\"mocosim_session\":1,\"protocol\":\"can\"}", 1, "dmc, dfmoco"},
      {"{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n{\"t_ns\":1,\"from\":\"x\",\"hex\":\"\"}", 2,
       "\"host\" or \"device\""},
      {"{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n{\"t_ns\":1,\"from\":\"host\",\"hex\":"
       "\"abc\"}",
       2, "hex"},
      {"{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n{\"t_ns\":5,\"from\":\"host\",\"hex\":\"\"}\n"
       "{\"t_ns\":4,\"from\":\"host\",\"hex\":\"\"}",
       3, "backwards"},
      {"{\"mocosim_session\":1,\"protocol\":\"dmc\"}\nnot json\n", 2, "not valid JSON"},
      {"{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n{\"t_ns\":1,\"fr\n"
       "{\"t_ns\":2,\"from\":\"host\",\"hex\":\"\"}",
       2, "not valid JSON"},                     // cut short, but not the last line: damaged
      {"{\"mocosim_sess", 1, "not valid JSON"},  // nothing whole to read
  };
  for (const auto& c : cases) {
    auto r = ParseSession(c.text);
    ASSERT_TRUE(std::holds_alternative<SessionError>(r)) << c.text;
    const auto& e = std::get<SessionError>(r);
    EXPECT_EQ(e.line, c.line) << c.text;
    EXPECT_NE(e.message.find(c.needle), std::string::npos) << e.message;
  }
}

TEST(SessionTest, WriterWritesPartialThenRenames) {
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("moco_session_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::create_directories(dir);
  const auto path = dir / "s.jsonl";
  std::filesystem::remove(path);
  SessionHeader h;
  h.protocol = Protocol::kStackshot;
  {
    SessionWriter w(path, h);
    SessionEntry e;
    e.t_ns = 3;
    e.from = Origin::kDevice;
    e.bytes = {0xaa, 0x10};
    w.Append(e);
    EXPECT_FALSE(std::filesystem::exists(path));
    const std::string partial = w.partial_path();
    EXPECT_EQ(partial.rfind(path.string() + ".partial-", 0), 0u) << partial;
    EXPECT_TRUE(std::filesystem::exists(partial));
    std::string err;
    EXPECT_TRUE(w.Finish(&err)) << err;
    EXPECT_FALSE(std::filesystem::exists(partial));
  }
  EXPECT_TRUE(std::filesystem::exists(path));
  const Session s = Ok(LoadSession(path));
  EXPECT_EQ(s.header.protocol, Protocol::kStackshot);
  ASSERT_EQ(s.entries.size(), 1u);
  EXPECT_EQ(s.entries[0].bytes, (wire::Bytes{0xaa, 0x10}));
  std::filesystem::remove_all(dir);
}

// A batch is the same file, line for line, as its entries appended one by
// one: traffic, decoded text that needs escaping, and events, in order.
TEST(SessionTest, WriterBatchAppendWritesTheSameLinesAsSingleAppends) {
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("moco_session_batch_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  std::filesystem::create_directories(dir);
  std::vector<SessionEntry> entries;
  SessionEntry host;
  host.t_ns = 1;
  host.bytes = {0x44, 0x46, 0x00};
  entries.push_back(host);
  SessionEntry device;
  device.t_ns = 2;
  device.from = Origin::kDevice;
  device.bytes = {0x0d, 0x0a};
  device.decoded = {"HI \"dmc16\"\tv2", "second"};
  entries.push_back(device);
  entries.push_back(SessionEntry::Event({{"t_ns", 3}, {"event", "host_link"}, {"detail", "open"}}));
  SessionHeader h;
  {
    SessionWriter one(dir / "one.jsonl", h);
    for (const SessionEntry& e : entries) one.Append(e);
    ASSERT_TRUE(one.Finish());
    SessionWriter batch(dir / "batch.jsonl", h);
    batch.Append(std::span<const SessionEntry>(entries.data(), 2));
    batch.Append(std::span<const SessionEntry>(entries.data() + 2, 1));
    batch.Append(std::span<const SessionEntry>());
    ASSERT_TRUE(batch.Finish());
  }
  auto read = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string text = read(dir / "batch.jsonl");
  EXPECT_EQ(text, read(dir / "one.jsonl"));
  const Session s = Ok(ParseSession(text));
  ASSERT_EQ(s.entries.size(), 3u);
  EXPECT_EQ(s.entries[1].decoded, device.decoded);
  EXPECT_TRUE(s.entries[2].is_event);
  std::filesystem::remove_all(dir);
}

TEST(SessionTest, WriterRefusesUnwritableDirectoryWithMessage) {
  SessionHeader h;
  try {
    SessionWriter w("/nonexistent-dir-for-moco/s.jsonl", h);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir-for-moco does not exist"),
              std::string::npos)
        << e.what();
  }
}

RC_GTEST_PROP(SessionProp, TrafficRoundTripsThroughText,
              (const std::vector<std::pair<bool, std::vector<uint8_t>>>& chunks)) {
  SessionHeader h;
  h.protocol = Protocol::kDfmoco;
  std::string text = HeaderToJson(h).dump() + "\n";
  int64_t t = 0;
  for (const auto& [from_host, bytes] : chunks) {
    SessionEntry e;
    e.t_ns = t;
    t += 1000;
    e.from = from_host ? Origin::kHost : Origin::kDevice;
    e.bytes = bytes;
    text += EntryToJson(e).dump() + "\n";
  }
  auto r = ParseSession(text);
  RC_ASSERT(std::holds_alternative<Session>(r));
  const auto& s = std::get<Session>(r);
  RC_ASSERT(s.header.protocol == Protocol::kDfmoco);
  RC_ASSERT(s.entries.size() == chunks.size());
  for (size_t i = 0; i < chunks.size(); ++i) {
    RC_ASSERT(s.entries[i].bytes == chunks[i].second);
    RC_ASSERT((s.entries[i].from == Origin::kHost) == chunks[i].first);
  }
}

// A traffic line written directly is EntryToJson's compact dump, byte for
// byte: any time, either side, any bytes, and decoded text of any bytes
// (quotes, backslashes, control characters, UTF-8 valid or not).
RC_GTEST_PROP(SessionProp, EntryLineIsTheJsonDumpByteForByte,
              (int64_t t_ns, bool from_host, const std::vector<uint8_t>& bytes,
               const std::vector<std::string>& decoded)) {
  SessionEntry e;
  e.t_ns = t_ns;
  e.from = from_host ? Origin::kHost : Origin::kDevice;
  e.bytes = bytes;
  e.decoded = decoded;
  // Printable text, quotes and backslashes among it, as decoded lines are.
  e.decoded.push_back(*rc::gen::container<std::string>(rc::gen::inRange<char>(0x20, 0x7f)));
  e.decoded.push_back(*rc::gen::element<std::string>("a\\b", "say \"hi\"", "tab\there", "\x7f",
                                                     "caf\xc3\xa9", "bad \xff utf-8"));
  std::string line;
  AppendEntryLine(e, line);
  RC_ASSERT(line ==
            EntryToJson(e).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

TEST(SessionTest, EventLinesAreTheirJsonDump) {
  const SessionEntry e =
      SessionEntry::Event({{"t_ns", 7}, {"event", "line_rate"}, {"baud", 57600}});
  std::string line;
  AppendEntryLine(e, line);
  EXPECT_EQ(line, "{\"baud\":57600,\"event\":\"line_rate\",\"t_ns\":7}\n");
}

TEST(SessionTest, ALineSwitchEventNamesTheProtocolAndRate) {
  const SessionEntry e =
      LineSwitchEvent(42, Protocol::kStackshotDfmoco, wire::LineSettings{.baud = 57600});
  std::string line;
  AppendEntryLine(e, line);
  EXPECT_EQ(line,
            "{\"baud\":57600,\"event\":\"line_switch\",\"protocol\":\"stackshot-dfmoco\","
            "\"t_ns\":42}\n");
  auto parsed =
      ParseSession("{\"mocosim_session\":1,\"protocol\":\"stackshot\"}\n" + line +
                   "{\"t_ns\":43,\"event\":\"line_switch\",\"protocol\":\"carrier-pigeon\"}\n"
                   "{\"t_ns\":44,\"event\":\"estop\",\"protocol\":\"dmc\"}\n");
  ASSERT_TRUE(std::holds_alternative<Session>(parsed));
  const Session& s = std::get<Session>(parsed);
  ASSERT_EQ(s.entries.size(), 3u);
  EXPECT_EQ(s.entries[0].t_ns, 42);
  EXPECT_EQ(LineSwitchOf(s.entries[0]), Protocol::kStackshotDfmoco);
  // A protocol this program does not know, and another event: no switch.
  EXPECT_EQ(LineSwitchOf(s.entries[1]), std::nullopt);
  EXPECT_EQ(LineSwitchOf(s.entries[2]), std::nullopt);
}

TEST(SessionTest, ALastLineCutShortKeepsTheLinesBeforeIt) {
  const std::string whole =
      "{\"mocosim_session\":1,\"protocol\":\"dmc\"}\n"
      "{\"t_ns\":1,\"from\":\"host\",\"hex\":\"44\"}\n";
  Session s = Ok(ParseSession(whole + "{\"t_ns\":2,\"from\":\"dev"));
  ASSERT_EQ(s.entries.size(), 1u);
  EXPECT_EQ(s.cut_line, 3u);
  EXPECT_EQ(SessionWarning(s),
            "line 3 is cut short (the recording did not finish); lines 1..2 are read");
  s = Ok(ParseSession(whole));
  EXPECT_EQ(s.cut_line, 0u);
  EXPECT_EQ(SessionWarning(s), "");
}

// Law: a recording cut at any byte after its header keeps every line that was
// whole, and says so when the last one was not (SessionWriter flushes line by
// line, docs/sessions.md).
RC_GTEST_PROP(SessionProp, ACutRecordingKeepsEveryWholeLine,
              (const std::vector<std::pair<bool, std::vector<uint8_t>>>& chunks)) {
  SessionHeader h;
  const std::string header = HeaderToJson(h).dump() + "\n";
  std::string text = header;
  std::vector<size_t> line_ends;  // offset just past each entry's newline
  for (size_t i = 0; i < chunks.size(); ++i) {
    SessionEntry e;
    e.t_ns = static_cast<int64_t>(i);
    e.from = chunks[i].first ? Origin::kHost : Origin::kDevice;
    e.bytes = chunks[i].second;
    text += EntryToJson(e).dump() + "\n";
    line_ends.push_back(text.size());
  }
  const size_t cut = *rc::gen::inRange(header.size(), text.size() + 1);
  auto r = ParseSession(std::string_view(text).substr(0, cut));
  RC_ASSERT(std::holds_alternative<Session>(r));
  const Session& s = std::get<Session>(r);
  // Lines whose closing brace is in: a line cut only at its newline is whole.
  size_t whole = 0;
  while (whole < line_ends.size() && line_ends[whole] - 1 <= cut) ++whole;
  RC_ASSERT(s.entries.size() == whole);
  for (size_t i = 0; i < whole; ++i) RC_ASSERT(s.entries[i].bytes == chunks[i].second);
  const bool cut_mid_line =
      whole < line_ends.size() && cut > (whole ? line_ends[whole - 1] : header.size());
  RC_ASSERT((s.cut_line != 0) == cut_mid_line);
  if (cut_mid_line) RC_ASSERT(s.cut_line == whole + 2);  // 1-based, after the header
}

// --- where a recording goes (docs/files.md) ----------------------------------------------

namespace fs = std::filesystem;

class RecordDir {
 public:
  RecordDir() {
    static int counter = 0;
    path_ = fs::temp_directory_path() /
            ("moco_record_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~RecordDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

SessionEntry HostBytes(int64_t t_ns, wire::Bytes b) {
  SessionEntry e;
  e.t_ns = t_ns;
  e.bytes = std::move(b);
  return e;
}

TEST(SessionWriterFiles, RecordingIntoAFifoWritesInPlaceAndTheFifoStaysAFifo) {
  RecordDir dir;
  const fs::path fifo = dir.path() / "record.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] {
    std::ifstream in(fifo, std::ios::binary);
    received.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  });
  {
    SessionWriter w(fifo, SessionHeader{});
    EXPECT_TRUE(w.partial_path().empty());
    w.Append(HostBytes(5, {0x44, 0x46}));
    std::string err;
    EXPECT_TRUE(w.Finish(&err)) << err;
  }
  reader.join();
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  const Session s = Ok(ParseSession(received));
  ASSERT_EQ(s.entries.size(), 1u);
  EXPECT_EQ(s.entries[0].bytes, (wire::Bytes{0x44, 0x46}));
}

TEST(SessionWriterFiles, ADirectoryIsRefusedAtOpenNamingItAndIsLeftAlone) {
  RecordDir dir;
  try {
    SessionWriter w(dir.path(), SessionHeader{});
    ADD_FAILURE() << "a directory was accepted as a recording";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(dir.path().string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(dir.path()));
  EXPECT_FALSE(fs::exists(dir.path().string() + ".corrupt"));
}

TEST(SessionWriterFiles, ASymlinkPlantedAtThePartialNameIsNeverWrittenThrough) {
  RecordDir dir;
  const fs::path victim = dir.path() / "victim.txt";
  { std::ofstream(victim) << "precious"; }
  const fs::path path = dir.path() / "s.jsonl";
  const uint64_t next = base::internal::NextTemporaryNumber();
  for (uint64_t n = next; n < next + 3; ++n) {
    fs::create_symlink(
        victim, path.string() + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(n));
  }
  // The old fixed name too.
  fs::create_symlink(victim, path.string() + ".partial");
  {
    SessionWriter w(path, SessionHeader{});
    w.Append(HostBytes(1, {0x01}));
    ASSERT_TRUE(w.Finish());
  }
  EXPECT_EQ(Slurp(victim), "precious");
  EXPECT_EQ(Ok(LoadSession(path)).entries.size(), 1u);
}

TEST(SessionWriterFiles, ReplacingAnExistingRecordingIsKnownAtOpen) {
  RecordDir dir;
  const fs::path path = dir.path() / "s.jsonl";
  { SessionWriter(path, SessionHeader{}).Finish(); }
  SessionWriter again(path, SessionHeader{});
  EXPECT_TRUE(again.replaces_existing());
  SessionWriter fresh(dir.path() / "new.jsonl", SessionHeader{});
  EXPECT_FALSE(fresh.replaces_existing());
}

TEST(SessionReaderFiles, DevicesDirectoriesAndEndlessLinesAreRefusedNotRead) {
  RecordDir dir;
  for (const std::string& p :
       {std::string("/dev/zero"), dir.path().string(), (dir.path() / "missing.jsonl").string()}) {
    const auto r = LoadSession(p);
    ASSERT_TRUE(std::holds_alternative<SessionError>(r)) << p;
    EXPECT_NE(std::get<SessionError>(r).message.find(p), std::string::npos)
        << std::get<SessionError>(r).message;
  }
  // A FIFO fed without a newline: stops at the line bound instead of growing.
  const fs::path fifo = dir.path() / "endless";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGPIPE);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::FILE* f = std::fopen(fifo.c_str(), "wb");
    const std::string block(65536, 'x');
    while (std::fwrite(block.data(), 1, block.size(), f) == block.size()) {
    }
    std::fclose(f);
  });
  const auto r = LoadSession(fifo);
  writer.join();
  ASSERT_TRUE(std::holds_alternative<SessionError>(r));
  EXPECT_NE(std::get<SessionError>(r).message.find("line 1 is longer than 4 MiB"),
            std::string::npos)
      << std::get<SessionError>(r).message;
}

}  // namespace
}  // namespace moco::session
