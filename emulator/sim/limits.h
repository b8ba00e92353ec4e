// Hardware limit sets (dmc-v2-protocol.txt MSG_MOTOR_SET_LIMITS "HW SET",
// flag 0x80 swaps high/low; MSG_MOTOR_HARD_STOP reasons 1 upper, 2 lower).
#ifndef MOCO_SIM_LIMITS_H_
#define MOCO_SIM_LIMITS_H_

#include <cstdint>
#include <optional>

namespace moco::sim {

// The two inputs of a hardware limit set.
enum class SwitchInput : uint8_t { kLow, kHigh };

// Where a limit set's two switches sit along the travel of the motor bound to
// it, in that motor's steps (part of the rig's description, not the protocol).
struct LimitSetPlacement {
  std::optional<int64_t> low_input_steps;
  std::optional<int64_t> high_input_steps;
};

// A motor's binding to a limit set, as MSG_MOTOR_SET_LIMITS carries it in
// one byte: the set number in the low 7 bits (0 = none) and 0x80 when the
// inputs are swapped, i.e. the set's LOW input guards the motor's upper end.
struct HardLimitBinding {
  static constexpr uint8_t kSwapFlag = 0x80;

  uint8_t set = 0;
  bool swapped = false;

  static HardLimitBinding FromWire(uint8_t hw_set) {
    return {static_cast<uint8_t>(hw_set & 0x7f), (hw_set & kSwapFlag) != 0};
  }
  uint8_t ToWire() const { return static_cast<uint8_t>(set | (swapped ? kSwapFlag : 0)); }
  bool operator==(const HardLimitBinding&) const = default;
};

}  // namespace moco::sim

#endif  // MOCO_SIM_LIMITS_H_
