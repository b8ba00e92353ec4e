// mocosim: emulated motion-control devices served over PTY or TCP.
#include <CLI/CLI.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  CLI::App app{"mocosim: emulated DMC-16, DFMoco Arduino and StackShot 3X devices"};
  app.set_version_flag("--version", "mocosim 0.1.0");
  app.require_subcommand(0, 1);
  CLI11_PARSE(app, argc, argv);
  if (app.get_subcommands().empty()) {
    std::puts(app.help().c_str());
  }
  return 0;
}
