// mococheck-build-native: builds an Arduino sketch folder against the host
// Arduino core into an executable for mococheck's native target (docs/firmware-
// ci.md): the .ino files prepared as the Arduino builder does (sketch_prep.h),
// the folder's .cpp/.c files and those of its src/ folder, the user's glue, the
// core's sources and the board's file, compiled and linked by one compiler run.
#include <fcntl.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "conformance/arduino/tools/sketch_prep.h"

extern char** environ;

namespace fs = std::filesystem;

namespace {

constexpr int kExitUsage = 2;
constexpr int kExitBuild = 1;

constexpr const char* kUsage =
    R"(mococheck-build-native: builds an Arduino sketch to run on mococheck's native target
usage: mococheck-build-native SKETCH_DIR [options]

Builds an Arduino sketch for mococheck's native target: the sketch runs on the
host against mococheck's Arduino core, in simulated time, and is then run with
  mococheck run --target native:EXECUTABLE --protocol dfmoco|dmc|stackshot

SKETCH_DIR is the sketch's folder: its .ino files (the one named after the
folder first, as the Arduino IDE orders them), its .cpp and .c files (C files
are compiled as C++, as the core's headers are C++) and those under src/.

options:
  --board NAME     the board whose API set and figures the sketch gets:
                   uno, esp32, teensy40, giga or generic (default: generic)
  -o PATH          the executable to write (default: SKETCHNAME.native in the
                   current folder); written whole or not at all
  --glue PATH      firmware-specific glue (repeatable): a .cpp/.c file to
                   compile with the sketch, a .h file to include before it, or
                   a folder whose headers the sketch may include and whose
                   .cpp/.c files are compiled (docs/firmware-ci.md)
  -D NAME[=VALUE]  a preprocessor definition for the sketch (repeatable)
  --cxx COMPILER   the C++ compiler (default: $CXX, else c++)
  --cxxflags FLAGS extra compiler flags, split at spaces (e.g. "-O0 -g
                   -fsanitize=address")
  --prepare-only   write only the prepared .ino source (C++) to -o
  -v, --verbose    print the compiler's command line
  -h, --help       this text
exit: 0 built, 1 the sketch did not build, 2 a usage error
)";

struct Options {
  fs::path sketch_dir;
  std::string board = "generic";
  fs::path output;
  std::vector<fs::path> glue;
  std::vector<std::string> defines;
  std::string cxx;
  std::vector<std::string> cxxflags;
  bool prepare_only = false;
  bool verbose = false;
};

int Usage(const std::string& problem) {
  std::cerr << "mococheck-build-native: " << problem << "\n(mococheck-build-native --help)\n";
  return kExitUsage;
}

// Where the core's sources are: $MOCO_ARDUINO_DIR, an installed copy beside
// the program (../share/mocosim/arduino), else the source tree it was built from.
fs::path CoreDir() {
  if (const char* env = getenv("MOCO_ARDUINO_DIR"); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path installed = self.parent_path().parent_path() / "share/mocosim/arduino";
    if (fs::is_regular_file(installed / "include/Arduino.h", ec)) return installed;
  }
  return MOCO_ARDUINO_SOURCE_DIR;
}

bool ReadText(const fs::path& path, std::string& text) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream s;
  s << in.rdbuf();
  text = s.str();
  return !in.bad();
}

bool HasExtension(const fs::path& p, std::initializer_list<const char*> exts) {
  const std::string e = p.extension().string();
  return std::any_of(exts.begin(), exts.end(), [&](const char* x) { return e == x; });
}

// The regular files of `dir` with one of `exts`, sorted; `recursive` for src/.
std::vector<fs::path> FilesIn(const fs::path& dir, std::initializer_list<const char*> exts,
                              bool recursive) {
  std::vector<fs::path> out;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return out;
  auto take = [&](const fs::directory_entry& e) {
    if (e.is_regular_file(ec) && HasExtension(e.path(), exts)) out.push_back(e.path());
  };
  if (recursive) {
    for (const auto& e : fs::recursive_directory_iterator(dir, ec)) take(e);
  } else {
    for (const auto& e : fs::directory_iterator(dir, ec)) take(e);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<std::string> SplitFlags(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

std::optional<int> ParseArgs(int argc, char** argv, Options& o) {
  std::vector<std::string> args(argv + 1, argv + argc);
  auto value = [&](size_t& i, const std::string& flag) -> std::optional<std::string> {
    if (i + 1 >= args.size() || args[i + 1].empty()) return std::nullopt;
    (void)flag;
    return args[++i];
  };
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (a == "--prepare-only") {
      o.prepare_only = true;
    } else if (a == "-v" || a == "--verbose") {
      o.verbose = true;
    } else if (a == "--board" || a == "-o" || a == "--glue" || a == "-D" || a == "--cxx" ||
               a == "--cxxflags") {
      const auto v = value(i, a);
      if (!v) return Usage(a + " needs a value");
      if (a == "--board") o.board = *v;
      if (a == "-o") o.output = *v;
      if (a == "--glue") o.glue.push_back(*v);
      if (a == "-D") o.defines.push_back(*v);
      if (a == "--cxx") o.cxx = *v;
      if (a == "--cxxflags") {
        const auto f = SplitFlags(*v);
        o.cxxflags.insert(o.cxxflags.end(), f.begin(), f.end());
      }
    } else if (a.starts_with("-D") && a.size() > 2) {
      o.defines.push_back(a.substr(2));
    } else if (!a.empty() && a[0] == '-') {
      return Usage("unknown option " + a);
    } else if (o.sketch_dir.empty()) {
      o.sketch_dir = a;
    } else {
      return Usage("one sketch folder only (\"" + o.sketch_dir.string() + "\" and \"" + a +
                   "\" given)");
    }
  }
  if (o.sketch_dir.empty()) return Usage("give the sketch's folder");
  return std::nullopt;
}

// Writes `text` to `path` through a temporary file renamed over it (never
// through a planted symlink, never over a non-regular file).
std::optional<std::string> WriteWhole(const fs::path& path, const std::string& text) {
  struct stat st {};
  if (lstat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISLNK(st.st_mode)) {
    return path.string() + " exists and is not a regular file; give another -o path";
  }
  const fs::path tmp = path.string() + ".tmp-" + std::to_string(getpid());
  // A new file only: never through a name someone planted beside the output.
  const int fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) return "cannot write " + tmp.string() + ": " + std::strerror(errno);
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      close(fd);
      unlink(tmp.c_str());
      return "cannot write " + tmp.string() + ": " + why;
    }
    done += static_cast<size_t>(n);
  }
  if (fsync(fd) != 0 || close(fd) != 0) {
    unlink(tmp.c_str());
    return "cannot write " + tmp.string() + ": " + std::strerror(errno);
  }
  if (rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    unlink(tmp.c_str());
    return "cannot write " + path.string() + ": " + why;
  }
  return std::nullopt;
}

int Run(const std::vector<std::string>& command, bool verbose) {
  if (verbose) {
    for (const auto& c : command) std::cerr << c << ' ';
    std::cerr << '\n';
  }
  std::vector<char*> argv;
  for (const auto& c : command) argv.push_back(const_cast<char*>(c.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawnp(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    std::cerr << "mococheck-build-native: cannot run the compiler " << command[0] << ": "
              << std::strerror(errno) << "; give one with --cxx or $CXX\n";
    return -1;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (const auto done = ParseArgs(argc, argv, o)) return *done;
  std::error_code ec;
  if (!fs::is_directory(o.sketch_dir, ec)) {
    return Usage("the sketch folder " + o.sketch_dir.string() + " is not a folder");
  }
  const fs::path sketch = fs::absolute(o.sketch_dir, ec).lexically_normal();
  std::string name = sketch.filename().string();
  if (name.empty()) name = sketch.parent_path().filename().string();
  const fs::path core = CoreDir();
  const fs::path board_header = core / "boards" / (o.board + ".h");
  if (!fs::is_regular_file(board_header, ec)) {
    std::string boards;
    for (const auto& b : FilesIn(core / "boards", {".h"}, false))
      boards += (boards.empty() ? "" : ", ") + b.stem().string();
    return Usage("no board \"" + o.board + "\"; the boards are: " + boards);
  }

  // The .ino files, prepared into one C++ source.
  std::vector<std::string> ino_names;
  for (const auto& p : FilesIn(sketch, {".ino"}, false)) ino_names.push_back(p.string());
  std::vector<moco::arduino::SketchFile> inos;
  for (const auto& n : moco::arduino::OrderInoFiles(ino_names, name + ".ino")) {
    moco::arduino::SketchFile f{n, ""};
    if (!ReadText(n, f.text)) return Usage("cannot read " + n);
    inos.push_back(std::move(f));
  }
  std::vector<fs::path> sources = FilesIn(sketch, {".cpp", ".cc", ".c"}, false);
  for (const auto& p : FilesIn(sketch / "src", {".cpp", ".cc", ".c"}, true)) sources.push_back(p);
  if (inos.empty() && sources.empty()) {
    return Usage(sketch.string() + " holds no .ino, .cpp or .c file: give the sketch's folder");
  }
  if (o.output.empty()) o.output = fs::current_path(ec) / (name + ".native");
  if (fs::is_directory(o.output, ec)) {
    return Usage("-o " + o.output.string() + " is a folder; give the executable's path");
  }

  std::string prepared;
  if (!inos.empty()) {
    auto result = moco::arduino::PrepareSketch(inos);
    if (result.index() == moco::arduino::kPrepareError) {
      std::cerr << "mococheck-build-native: " << std::get<1>(result) << "\n";
      return kExitBuild;
    }
    prepared = std::move(std::get<0>(result));
  }
  if (o.prepare_only) {
    if (auto err = WriteWhole(o.output, prepared)) return Usage(*err);
    return 0;
  }

  char tmpl[] = "/tmp/mococheck-build-native-XXXXXX";
  if (mkdtemp(tmpl) == nullptr) return Usage(std::string("cannot make a build folder in /tmp"));
  const fs::path work = tmpl;
  if (!prepared.empty()) {
    const fs::path p = work / (name + ".ino.cpp");
    if (auto err = WriteWhole(p, prepared)) return Usage(*err);
    sources.insert(sources.begin(), p);
  }

  std::string cxx = o.cxx;
  if (cxx.empty()) cxx = getenv("CXX") != nullptr && *getenv("CXX") != '\0' ? getenv("CXX") : "c++";
  std::vector<std::string> cmd = {cxx,
                                  "-std=gnu++17",
                                  "-O2",
                                  "-g",
                                  "-include",
                                  board_header.string(),
                                  "-I" + (core / "include").string(),
                                  "-I" + core.parent_path().parent_path().string(),
                                  "-I" + sketch.string(),
                                  "-I" + (sketch / "src").string()};
  for (const auto& d : o.defines) cmd.push_back("-D" + d);
  std::vector<fs::path> glue_sources;
  for (const auto& g : o.glue) {
    if (fs::is_directory(g, ec)) {
      cmd.push_back("-I" + fs::absolute(g, ec).string());
      for (const auto& p : FilesIn(g, {".cpp", ".cc", ".c"}, false)) glue_sources.push_back(p);
    } else if (HasExtension(g, {".h", ".hpp"})) {
      cmd.push_back("-include");
      cmd.push_back(fs::absolute(g, ec).string());
    } else if (HasExtension(g, {".cpp", ".cc", ".c"}) && fs::is_regular_file(g, ec)) {
      glue_sources.push_back(g);
    } else {
      return Usage("--glue " + g.string() + " is not a folder, a .h or a .cpp/.c file");
    }
  }
  cmd.insert(cmd.end(), o.cxxflags.begin(), o.cxxflags.end());
  cmd.push_back("-x");
  cmd.push_back("c++");
  for (const auto& s : sources) cmd.push_back(s.string());
  for (const auto& s : glue_sources) cmd.push_back(s.string());
  for (const auto& s : FilesIn(core / "core", {".cpp"}, false)) cmd.push_back(s.string());
  cmd.push_back((core / "boards" / (o.board + ".cpp")).string());
  const fs::path tmp_out = work / "firmware";
  cmd.push_back("-o");
  cmd.push_back(tmp_out.string());

  const int rc = Run(cmd, o.verbose);
  int exit_code = 0;
  if (rc != 0) {
    std::cerr << "mococheck-build-native: the sketch did not build (the compiler's messages are "
                 "above; -v shows its command)\n";
    exit_code = kExitBuild;
  } else {
    std::string image;
    if (!ReadText(tmp_out, image)) {
      std::cerr << "mococheck-build-native: the compiler wrote no executable\n";
      exit_code = kExitBuild;
    } else if (auto err = WriteWhole(o.output, image)) {
      std::cerr << "mococheck-build-native: " << *err << "\n";
      exit_code = kExitUsage;
    } else {
      chmod(o.output.c_str(), 0755);
      std::cout << "built " << o.output.string() << " (board " << o.board
                << "): run it with mococheck run --target native:" << o.output.string()
                << " --protocol PROTOCOL\n";
    }
  }
  fs::remove_all(work, ec);
  return exit_code;
}
