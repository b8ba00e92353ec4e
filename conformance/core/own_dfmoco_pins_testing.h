// For the simavr tests: the pin judging the CLI sets up for `--board
// fixtures/boards/own-dfmoco.json --driver a4988`, the board file read from
// the source tree (MOCO_SOURCE_DIR, else the working directory).
#ifndef MOCO_CONFORMANCE_CORE_OWN_DFMOCO_PINS_TESTING_H_
#define MOCO_CONFORMANCE_CORE_OWN_DFMOCO_PINS_TESTING_H_

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <variant>

#include "conformance/core/pin_judge.h"
#include "conformance/targets/simavr_pins.h"

namespace moco::conformance {

inline PinJudgeOptions OwnDfmocoPins() {
  const char* root = std::getenv("MOCO_SOURCE_DIR");
  const std::string path =
      std::string(root != nullptr ? root : ".") + "/fixtures/boards/own-dfmoco.json";
  PinJudgeOptions pins;
  auto board = LoadBoard(path);
  if (const auto* err = std::get_if<std::string>(&board)) {
    ADD_FAILURE() << *err << " (is MOCO_SOURCE_DIR the source tree?)";
    return pins;
  }
  auto driver = LoadDriver("a4988");
  if (const auto* err = std::get_if<std::string>(&driver)) {
    ADD_FAILURE() << *err;
    return pins;
  }
  pins.board = std::get<Board>(board);
  pins.driver = std::get<DriverProfile>(driver);
  return pins;
}

}  // namespace moco::conformance

#endif  // MOCO_CONFORMANCE_CORE_OWN_DFMOCO_PINS_TESTING_H_
