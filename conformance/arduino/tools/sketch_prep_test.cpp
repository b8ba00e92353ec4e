// Tests of the Arduino sketch preprocessing (Arduino CLI "Sketch build process"): the
// prepared source is checked as text and by compiling it with the system C++ compiler
// against a small fake Arduino.h.
#include "conformance/arduino/tools/sketch_prep.h"

#include <gtest/gtest.h>
#include <stdlib.h>  // mkdtemp

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace moco::arduino {
namespace {

constexpr char kFakeArduinoH[] = R"(#pragma once
#define HIGH 1
#define LOW 0
#define INPUT 0
#define OUTPUT 1
#define ISR(vector, ...) extern "C" void vector(void)
void pinMode(int pin, int mode);
void digitalWrite(int pin, int value);
int digitalRead(int pin);
void delay(unsigned long ms);
)";

// The prepared source; a failure (and "") when PrepareSketch reports an error.
std::string Prepared(const std::vector<SketchFile>& files) {
  const auto result = PrepareSketch(files);
  if (result.index() != kPreparedSource) {
    ADD_FAILURE() << "unexpected error: " << std::get<kPrepareError>(result);
    return "";
  }
  return std::get<kPreparedSource>(result);
}

// The error message; a failure (and "") when PrepareSketch succeeds.
std::string PrepareError(const std::vector<SketchFile>& files) {
  const auto result = PrepareSketch(files);
  if (result.index() != kPrepareError) {
    ADD_FAILURE() << "expected an error, got:\n" << std::get<kPreparedSource>(result);
    return "";
  }
  return std::get<kPrepareError>(result);
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// Generated prototypes: a line ending in ';' right after a #line directive. (Sketches in
// these tests never start a file with such a line.)
std::vector<std::string> Prototypes(const std::string& source) {
  const std::vector<std::string> lines = Lines(source);
  std::vector<std::string> prototypes;
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    if (lines[i - 1].rfind("#line ", 0) == 0 && !line.empty() && line.back() == ';' &&
        line[0] != '#') {
      prototypes.push_back(line);
    }
  }
  return prototypes;
}

// The plain concatenation the builder would produce without prototypes (for files that
// end with a newline).
std::string Concatenation(const std::vector<SketchFile>& files) {
  std::string out = "#include <Arduino.h>\n";
  for (const SketchFile& file : files) out += "#line 1 \"" + file.name + "\"\n" + file.text;
  return out;
}

void WriteFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Compiles prepared sources (syntax only) with the system compiler in a scratch directory
// that holds the fake Arduino.h.
class CompileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (std::system("c++ --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "no c++ compiler";
    std::string pattern = (std::filesystem::temp_directory_path() / "sketch_prep_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
    WriteFile(dir_ / "Arduino.h", kFakeArduinoH);
  }
  void TearDown() override {
    std::error_code ignored;
    if (!dir_.empty()) std::filesystem::remove_all(dir_, ignored);
  }

  // The compiler's exit status (0: compiles); its diagnostics go to `diagnostics`.
  int Compile(const std::string& source, std::string* diagnostics = nullptr,
              const std::string& flags = "") {
    const std::filesystem::path file = dir_ / "sketch.cpp";
    const std::filesystem::path log = dir_ / "diagnostics.txt";
    WriteFile(file, source);
    const std::string command = "c++ -std=gnu++17 -fsyntax-only " + flags + " -I'" + dir_.string() +
                                "' '" + file.string() + "' 2>'" + log.string() + "'";
    const int status = std::system(command.c_str());
    if (diagnostics != nullptr) *diagnostics = ReadFile(log);
    return status;
  }

  std::filesystem::path dir_;
};

TEST(PrepareSketchTest, GoldenOutputForBlink) {
  const std::vector<SketchFile> files = {{"/s/Blink/Blink.ino",
                                          "// Blink\n"
                                          "#define LED 13\n"
                                          "\n"
                                          "void setup() {\n"
                                          "  pinMode(LED, OUTPUT);\n"
                                          "}\n"
                                          "\n"
                                          "void loop() { blink(2); }\n"
                                          "\n"
                                          "void blink(int times) {\n"
                                          "  while (times--) digitalWrite(LED, HIGH);\n"
                                          "}\n"},
                                         {"/s/Blink/more.ino", "int more() { return 1; }"}};
  EXPECT_EQ(Prepared(files),
            "#include <Arduino.h>\n"
            "#line 1 \"/s/Blink/Blink.ino\"\n"
            "// Blink\n"
            "#define LED 13\n"
            "\n"
            "#line 4 \"/s/Blink/Blink.ino\"\n"
            "void setup();\n"
            "#line 8 \"/s/Blink/Blink.ino\"\n"
            "void loop();\n"
            "#line 10 \"/s/Blink/Blink.ino\"\n"
            "void blink(int times);\n"
            "#line 1 \"/s/Blink/more.ino\"\n"
            "int more();\n"
            "#line 4 \"/s/Blink/Blink.ino\"\n"
            "void setup() {\n"
            "  pinMode(LED, OUTPUT);\n"
            "}\n"
            "\n"
            "void loop() { blink(2); }\n"
            "\n"
            "void blink(int times) {\n"
            "  while (times--) digitalWrite(LED, HIGH);\n"
            "}\n"
            "#line 1 \"/s/Blink/more.ino\"\n"
            "int more() { return 1; }\n");
}

TEST_F(CompileTest, CallBeforeDefinitionCompilesOnlyWithPrototypes) {
  const std::vector<SketchFile> files = {{"/s/Blink/Blink.ino",
                                          "// Blinks twice a second.\n"
                                          "void setup() { pinMode(13, OUTPUT); }\n"
                                          "void loop() { blinkTwice(13); }\n"
                                          "void blinkTwice(int pin) {\n"
                                          "  for (int i = 0; i < 2; ++i) {\n"
                                          "    digitalWrite(pin, HIGH);\n"
                                          "    delay(100);\n"
                                          "  }\n"
                                          "}\n"}};
  std::string diagnostics;
  EXPECT_EQ(Compile(Prepared(files), &diagnostics), 0) << diagnostics;
  EXPECT_NE(Compile(Concatenation(files), &diagnostics), 0);
  EXPECT_NE(diagnostics.find("blinkTwice"), std::string::npos) << diagnostics;
}

TEST_F(CompileTest, PrototypesFollowStructUsedInParameter) {
  const std::vector<SketchFile> files = {{"/s/Drive/Drive.ino",
                                          "#include <Arduino.h>\n"
                                          "struct Motor {\n"
                                          "  int pin;\n"
                                          "};\n"
                                          "Motor left{5};\n"
                                          "void setup() { drive(left, 3); }\n"
                                          "void loop() {}\n"
                                          "void drive(Motor& m, int speed) {\n"
                                          "  digitalWrite(m.pin, speed);\n"
                                          "}\n"}};
  const std::string source = Prepared(files);
  const size_t prototype = source.find("\nvoid drive(Motor& m, int speed);\n");
  ASSERT_NE(prototype, std::string::npos) << source;
  EXPECT_GT(prototype, source.find("struct Motor {"));
  EXPECT_GT(prototype, source.find("Motor left{5};"));
  EXPECT_LT(prototype, source.find("void setup() {"));
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
}

TEST_F(CompileTest, LineDirectivesMapErrorsToSketchFiles) {
  const std::vector<SketchFile> files = {{"/s/Demo/Demo.ino",
                                          "// Demo\n"
                                          "void setup() {\n"
                                          "  helper();\n"
                                          "}\n"
                                          "void loop() {\n"
                                          "  int broken = ;\n"
                                          "}\n"},
                                         {"/s/Demo/helpers.ino",
                                          "// helpers\n"
                                          "\n"
                                          "void helper() {\n"
                                          "  pinMode(13, OUTPUT);\n"
                                          "}\n"
                                          "\n"
                                          "void other() { undeclared_name(); }\n"}};
  std::string diagnostics;
  EXPECT_NE(Compile(Prepared(files), &diagnostics), 0);
  EXPECT_NE(diagnostics.find("/s/Demo/helpers.ino:7:"), std::string::npos) << diagnostics;
  EXPECT_NE(diagnostics.find("/s/Demo/Demo.ino:6:"), std::string::npos) << diagnostics;
  // Those two and nothing else: the call to helper() before its definition is fine.
  size_t errors = 0;
  for (size_t at = diagnostics.find("error:"); at != std::string::npos;
       at = diagnostics.find("error:", at + 1)) {
    ++errors;
  }
  EXPECT_EQ(errors, 2u) << diagnostics;
}

TEST_F(CompileTest, CommentsStringsAndDirectivesHideCode) {
  const std::vector<SketchFile> files = {{"/s/Hide/Hide.ino",
                                          "// void fake1() {\n"
                                          "/* void fake2() {\n"
                                          "   } */\n"
                                          "const char* s1 = \"void fake3() { \\\" }\";\n"
                                          "const char c1 = '{';\n"
                                          "const char c2 = '\\'';\n"
                                          "const char* s2 = R\"x(void fake4() { )\" )x\";\n"
                                          "#define FAKE5 void fake5() { \\\n"
                                          "  }\n"
                                          "const long big = 1'000'000;\n"
                                          "// continued \\\n"
                                          "void fake6() {\n"
                                          "void setup() {}\n"
                                          "void loop() {}\n"}};
  const std::string source = Prepared(files);
  EXPECT_EQ(Prototypes(source), (std::vector<std::string>{"void setup();", "void loop();"}))
      << source;
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
}

TEST_F(CompileTest, NoPrototypeForDefaultsTemplatesIsrMembersOperators) {
  const std::vector<SketchFile> files = {
      {"/s/Kinds/Kinds.ino",
       "// Kinds of definitions\n"
       "struct Foo { void bar(); int v; };\n"
       "void Foo::bar() { v = 1; }\n"
       "bool operator==(const Foo& a, const Foo& b) { return a.v == b.v; }\n"
       "template <typename T>\n"
       "T twice(T x) { return x + x; }\n"
       "ISR(TIMER1_COMPA_vect) { digitalWrite(13, HIGH); }\n"
       "void withDefault(int pin = 13) { digitalWrite(pin, LOW); }\n"
       "void setup() { plain(); withDefault(); }\n"
       "void loop() { twice(2); }\n"
       "void plain() {}\n"}};
  const std::string source = Prepared(files);
  EXPECT_EQ(Prototypes(source),
            (std::vector<std::string>{"void setup();", "void loop();", "void plain();"}))
      << source;
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
}

TEST_F(CompileTest, AlreadyDeclaredFunctionGetsNoDuplicate) {
  const std::vector<SketchFile> files = {{"/s/Decl/Decl.ino",
                                          "// Declared up front\n"
                                          "void helper(int   pin);\n"
                                          "void setup() { helper(13); helper(13L); }\n"
                                          "void loop() {}\n"
                                          "void helper(int pin /* the LED */) {}\n"
                                          "void helper(long pin) {}\n"}};
  const std::string source = Prepared(files);
  EXPECT_EQ(Prototypes(source),
            (std::vector<std::string>{"void setup();", "void loop();", "void helper(long pin);"}))
      << source;
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
}

TEST_F(CompileTest, ConditionalDefinitionsGetConditionalPrototypes) {
  const std::vector<SketchFile> files = {{"/s/Radio/Radio.ino",
                                          "// Builds with and without the radio\n"
                                          "#ifdef USE_RADIO\n"
                                          "struct Radio { int channel; };\n"
                                          "Radio radio{7};\n"
                                          "#endif\n"
                                          "void setup() { start(); }\n"
                                          "void loop() {}\n"
                                          "void start() {\n"
                                          "#ifdef USE_RADIO\n"
                                          "  announce(radio);\n"
                                          "#endif\n"
                                          "  report();\n"
                                          "}\n"
                                          "#ifdef USE_RADIO\n"
                                          "void announce(Radio& r) { r.channel = 1; }\n"
                                          "void report() { announce(radio); }\n"
                                          "#else\n"
                                          "void report() { delay(1); }\n"
                                          "#endif\n"}};
  const std::string source = Prepared(files);
  EXPECT_NE(source.find("#ifdef USE_RADIO\n#line 15 \"/s/Radio/Radio.ino\"\n"
                        "void announce(Radio& r);\n"),
            std::string::npos)
      << source;
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics, "-DUSE_RADIO"), 0) << source << diagnostics;
}

TEST(PrepareSketchTest, IfZeroGroupsAreSkipped) {
  const std::vector<SketchFile> files = {{"/s/Old/Old.ino",
                                          "// Old code kept around\n"
                                          "void setup() {}\n"
                                          "#if 0\n"
                                          "Don't build this: it's \"old.\n"
                                          "#ifdef X\n"
                                          "#else\n"
                                          "#endif\n"
                                          "void hidden() {}\n"
                                          "#else\n"
                                          "void shown() {}\n"
                                          "#endif\n"}};
  const std::string source = Prepared(files);
  EXPECT_EQ(Prototypes(source), (std::vector<std::string>{"void setup();", "void shown();"}))
      << source;
  EXPECT_NE(source.find("#if 0\n#else\n#line 10 \"/s/Old/Old.ino\"\nvoid shown();\n#endif\n"),
            std::string::npos)
      << source;
}

TEST_F(CompileTest, TypeDeclaredAfterTheBlockSuppressesPrototype) {
  const std::vector<SketchFile> files = {{"/s/Late/Late.ino",
                                          "// A type declared between functions\n"
                                          "void setup() { show(); }\n"
                                          "void loop() {}\n"
                                          "struct Point { int x; };\n"
                                          "void draw(Point p) { delay(p.x); }\n"
                                          "void show() { draw(Point{1}); }\n"}};
  const std::string source = Prepared(files);
  EXPECT_EQ(Prototypes(source),
            (std::vector<std::string>{"void setup();", "void loop();", "void show();"}))
      << source;
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
}

TEST(PrepareSketchTest, ErrorsNameFileAndLine) {
  EXPECT_EQ(PrepareError({{"/s/E/E.ino", "void setup() {}\n"},
                          {"/s/E/two.ino", "// ok\n\nint x;\n/* not closed\n\n"}}),
            "/s/E/two.ino:4: unterminated /* comment");
  EXPECT_EQ(PrepareError({{"a.ino", "int a;\nconst char* s = \"abc;\nint b;\n"}}),
            "a.ino:2: missing terminating \" character");
  EXPECT_EQ(PrepareError({{"a.ino", "char c = 'x;\n"}}),
            "a.ino:1: missing terminating ' character");
  EXPECT_EQ(PrepareError({{"a.ino", "\nauto s = R\"x(never closed)\";\n"}}),
            "a.ino:2: unterminated raw string");
  EXPECT_EQ(PrepareError({{"a.ino", "void f() {\n}\n}\n"}}), "a.ino:3: '}' without a matching '{'");
  EXPECT_EQ(PrepareError({{"a.ino", "int x;\nvoid f() {\n  if (x) {\n}\n"}}),
            "a.ino:2: '{' is never closed");
  EXPECT_EQ(PrepareError({}), "sketch has no .ino files");
}

TEST(PrepareSketchTest, BracesSplitAcrossConditionalBranchesAreAccepted) {
  const std::string source = Prepared({{"/s/C/C.ino",
                                        "// Two headers, one body\n"
                                        "void setup() {}\n"
                                        "#ifdef FAST\n"
                                        "void step(int n) {\n"
                                        "#else\n"
                                        "void step(long n) {\n"
                                        "#endif\n"
                                        "  delay(n);\n"
                                        "}\n"
                                        "void after() {}\n"}});
  EXPECT_EQ(Prototypes(source), (std::vector<std::string>{"void setup();", "void step(int n);",
                                                          "void step(long n);", "void after();"}))
      << source;
}

TEST_F(CompileTest, BracesInsideAStatementDoNotEndIt) {
  const std::vector<SketchFile> files = {{"/s/Expr/Expr.ino",
                                          "// Braces in expressions at file scope\n"
                                          "struct Motor { int pin; };\n"
                                          "int table[] = {1, 2};\n"
                                          "void setup() { pinOf(Motor{3}); }\n"
                                          "void loop() {}\n"
                                          "decltype(Motor{}.pin) pinOf(const Motor& m) {\n"
                                          "  return m.pin;\n"
                                          "}\n"}};
  const std::string source = Prepared(files);
  EXPECT_EQ(Prototypes(source),
            (std::vector<std::string>{"void setup();", "void loop();",
                                      "decltype(Motor{}.pin) pinOf(const Motor& m);"}))
      << source;
  std::string diagnostics;
  EXPECT_EQ(Compile(source, &diagnostics), 0) << source << diagnostics;
}

TEST(PrepareSketchTest, EmptyFilesNamesAndMissingNewlines) {
  EXPECT_EQ(Prepared({{"/s/E/E.ino", ""}}), "#include <Arduino.h>\n#line 1 \"/s/E/E.ino\"\n");
  EXPECT_EQ(Prepared({{"C:\\Sketch\\a\"b.ino", "\xEF\xBB\xBFint x;"}}),
            "#include <Arduino.h>\n#line 1 \"C:\\\\Sketch\\\\a\\\"b.ino\"\nint x;\n");
  // A file ending in a backslash must not splice the next file's #line onto its last line.
  EXPECT_EQ(Prepared({{"a.ino", "#define X 1 \\"}, {"b.ino", "int y = X;\n"}}),
            "#include <Arduino.h>\n#line 1 \"a.ino\"\n#define X 1 \\\n\n"
            "#line 1 \"b.ino\"\nint y = X;\n");
}

TEST(OrderInoFilesTest, MainFirstThenByteOrder) {
  EXPECT_EQ(OrderInoFiles({"b.ino", "Blink.ino", "a.ino", "Zeta.ino", "_x.ino", "\xC3\xA9.ino"},
                          "Blink.ino"),
            (std::vector<std::string>{"Blink.ino", "Zeta.ino", "_x.ino", "a.ino", "b.ino",
                                      "\xC3\xA9.ino"}));
  EXPECT_EQ(
      OrderInoFiles({"/p/Blink/util.ino", "/p/Blink/Blink.ino", "/p/Blink/a.ino"}, "Blink.ino"),
      (std::vector<std::string>{"/p/Blink/Blink.ino", "/p/Blink/a.ino", "/p/Blink/util.ino"}));
  EXPECT_EQ(OrderInoFiles({"b.ino", "a.ino"}, "Main.ino"),
            (std::vector<std::string>{"a.ino", "b.ino"}));
  EXPECT_EQ(OrderInoFiles({"xBlink.ino", "Blink.ino"}, "Blink.ino"),
            (std::vector<std::string>{"Blink.ino", "xBlink.ino"}));
}

// Law: the preprocessor only inserts. Whatever it accepts, the output is the plain
// concatenation with one contiguous chunk added.
TEST(PrepareSketchTest, PropertyOutputIsConcatenationPlusOneChunk) {
  static const char* const kLines[] = {"void f%(int a) {",
                                       "}",
                                       "  g%();",
                                       "// comment {",
                                       "/* block } */",
                                       "/* open",
                                       "close */",
                                       "#ifdef X",
                                       "#else",
                                       "#endif",
                                       "#if 0",
                                       "struct S% { int v; }; void h%() {",
                                       "int v% = 3;",
                                       "template <class T> T t%(T x) { return x; }",
                                       "const char* s = \"{ void q() {\";",
                                       "ISR(V%) {",
                                       "void d%(int a = 1) {",
                                       "static inline long k%(S% s,",
                                       "  int b) {",
                                       "",
                                       "'",
                                       "\\"};
  std::mt19937 rng(20240611);
  int accepted = 0;
  for (int round = 0; round < 3000; ++round) {
    std::vector<SketchFile> files(1 + rng() % 3);
    for (size_t f = 0; f < files.size(); ++f) {
      files[f].name = "/s/P/p" + std::to_string(f) + ".ino";
      const int lines = static_cast<int>(rng() % 12);
      for (int l = 0; l < lines; ++l) {
        std::string line = kLines[rng() % std::size(kLines)];
        for (size_t at; (at = line.find('%')) != std::string::npos;) {
          line[at] = static_cast<char>('0' + rng() % 4);
        }
        if (line == "\\") line = "int w; \\";  // a splice into the next line
        files[f].text += line + "\n";
      }
      const std::string& text = files[f].text;
      if (text.size() >= 2 && text.compare(text.size() - 2, 2, "\\\n") == 0) {
        files[f].text += "\n";  // keep the concatenation free of end-of-file fixes
      }
    }
    const auto result = PrepareSketch(files);
    if (result.index() != kPreparedSource) continue;
    ++accepted;
    const std::string& out = std::get<kPreparedSource>(result);
    const std::string plain = Concatenation(files);
    ASSERT_GE(out.size(), plain.size());
    size_t prefix = 0;
    while (prefix < plain.size() && out[prefix] == plain[prefix]) ++prefix;
    size_t suffix = 0;
    while (suffix < plain.size() - prefix &&
           out[out.size() - 1 - suffix] == plain[plain.size() - 1 - suffix]) {
      ++suffix;
    }
    ASSERT_EQ(prefix + suffix, plain.size()) << "round " << round << "\n" << out;
  }
  EXPECT_GT(accepted, 300);
}

TEST(PrepareSketchTest, NeverCrashesOnJunk) {
  std::mt19937 rng(7);
  static const char* const kPieces[] = {
      "{",  "}",    "(",     ")",        "[",  "]",  ";",    "/*",      "*/",       "//",
      "\"", "'",    "R\"x(", ")x\"",     "\\", "\n", "\r\n", "#if 0\n", "#else\n",  "#endif\n",
      "#",  "void", " f",    "template", "<",  ">",  "=",    "::",      "operator", "\xEF\xBB\xBF"};
  for (int round = 0; round < 3000; ++round) {
    std::vector<SketchFile> files(1 + rng() % 2);
    for (SketchFile& file : files) {
      file.name = "junk.ino";
      const int pieces = static_cast<int>(rng() % 40);
      for (int p = 0; p < pieces; ++p) {
        if (rng() % 4 == 0) {
          file.text += static_cast<char>(rng() % 256);
        } else {
          file.text += kPieces[rng() % std::size(kPieces)];
        }
      }
    }
    const auto result = PrepareSketch(files);
    if (result.index() == kPreparedSource) {
      ASSERT_EQ(std::get<kPreparedSource>(result).rfind("#include <Arduino.h>\n#line 1 ", 0), 0u);
    } else {
      ASSERT_EQ(std::get<kPrepareError>(result).rfind("junk.ino:", 0), 0u);
    }
  }
}

// Law: a sketch whose functions call each other in any order, spread over several files,
// compiles once prepared.
TEST_F(CompileTest, PropertyRandomCallGraphsCompile) {
  std::mt19937 rng(1234);
  for (int round = 0; round < 4; ++round) {
    const int functions = 6 + static_cast<int>(rng() % 10);
    std::vector<std::string> definitions;
    for (int f = 0; f < functions; ++f) {
      std::string body;
      for (int calls = static_cast<int>(rng() % 3); calls > 0; --calls) {
        body += "  f" + std::to_string(rng() % functions) + "(x - 1);\n";
      }
      definitions.push_back("/* f" + std::to_string(f) + " */\nstatic int f" + std::to_string(f) +
                            "(int x) {\n" + body + "  return x;\n}\n");
    }
    definitions.push_back("void setup() { f" + std::to_string(rng() % functions) + "(3); }\n");
    definitions.push_back("void loop() { f" + std::to_string(rng() % functions) + "(4); }\n");
    std::shuffle(definitions.begin(), definitions.end(), rng);
    std::vector<SketchFile> files(1 + rng() % 3);
    for (size_t f = 0; f < files.size(); ++f) {
      files[f].name = "/s/G/g" + std::to_string(f) + ".ino";
      files[f].text = "// part " + std::to_string(f) + "\n";
    }
    for (const std::string& definition : definitions) {
      files[rng() % files.size()].text += definition;
    }
    const std::string source = Prepared(files);
    std::string diagnostics;
    ASSERT_EQ(Compile(source, &diagnostics, "-Wno-unused-function"), 0) << source << diagnostics;
  }
}

TEST(PrepareSketchTest, MegabyteSketchesAreFast) {
  std::string functions = "// many functions\n";
  for (int f = 0; functions.size() < (1 << 20); ++f) {
    functions +=
        "void f" + std::to_string(f) + "(int a) { f" + std::to_string(f + 1) + "(a); } // note\n";
  }
  std::string nested;
  while (nested.size() < (1 << 20)) nested += "#if 1\nvoid a() {}\n";
  const std::vector<std::string> sketches = {
      functions,
      nested,
      std::string(1 << 20, '{'),
      std::string(1 << 20, '('),
      std::string(1 << 20, '\n'),
      "void f() {" + std::string(1 << 20, '[') + "\n}\n",
      "/*" + std::string(1 << 20, '*'),
  };
  for (const std::string& text : sketches) {
    const auto start = std::chrono::steady_clock::now();
    const auto result = PrepareSketch({{"/s/Big/Big.ino", text}});
    const auto elapsed = std::chrono::steady_clock::now() - start;
    // Linear work takes milliseconds; a quadratic walk over 1 MB would take minutes.
    EXPECT_LT(elapsed, std::chrono::seconds(2)) << text.substr(0, 40);
    if (text == functions) {
      ASSERT_EQ(result.index(), kPreparedSource);
      EXPECT_NE(std::get<kPreparedSource>(result).find("\nvoid f12345(int a);\n"),
                std::string::npos);
    }
  }
}

}  // namespace
}  // namespace moco::arduino
