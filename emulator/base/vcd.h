// Value Change Dump text (IEEE 1364 section 18, the 4-state subset a logic
// analyser needs: one-bit wires, 0 and 1): the waveforms of watched firmware
// pins (mococheck --vcd) and of an emulated device's step model (mocosim
// --vcd), read by GTKWave, PulseView and `sigrok-cli -I vcd`.
#ifndef MOCO_BASE_VCD_H_
#define MOCO_BASE_VCD_H_

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace moco::base {

struct VcdWire {
  std::string name;  // e.g. "m1_step"; spaces become '_'
  bool initial = false;
  // (time in ns, level), times non-decreasing; repeats of a level are dropped.
  std::vector<std::pair<int64_t, bool>> changes;
};

// A whole dump with a 1 ns timescale, every wire in one scope `scope`, the
// initial levels in $dumpvars and the changes of all wires merged in time
// order. `comment` (one line) goes into a $comment section. Deterministic: no
// $date.
std::string VcdText(std::string_view scope, std::string_view comment,
                    const std::vector<VcdWire>& wires);

// The identifier code of wire `index`: '!' .. '~', then two characters, ...
std::string VcdIdentifier(size_t index);

}  // namespace moco::base

#endif  // MOCO_BASE_VCD_H_
