// The DFMoco rule catalogue (dfmoco-protocol.txt "Message Format", "Messages",
// "Go-Motion", "Notes"; ERRATA dfmoco 1-5; FACTS "DFMoco"): the sketch's line
// and reply grammar, `mp` while moving and the dialect differences. Clauses
// are quoted from the protocol text; where it is silent the FACTS or ERRATA
// reading is quoted instead and the source says so.
#include "conformance/rules/catalogue.h"
#include "conformance/rules/dfmoco_needs.h"

#include <charconv>

namespace moco::conformance {
namespace {

using L = Level;
using N = DfmocoNeeds;

const std::vector<Rule> kRules = {
    // --- Lines ("Message Format") ---
    {"DFM-LINE-001", L::kMust, N::kNothing, "Every device line ends in \"\\r\\n\"",
     "Messages are in ASCII text, with trailing \\r\\n", "Message Format; ERRATA 2.1"},
    {"DFM-LINE-002", L::kMust, N::kNothing,
     "Device lines hold printable ASCII only (0x20-0x7E before the terminator)",
     "Messages are in ASCII text, with trailing \\r\\n", "Message Format"},
    {"DFM-LINE-003", L::kMust, N::kNothing,
     "The device never leaves a line unfinished (every line it starts ends in its terminator)",
     "Messages are in ASCII text, with trailing \\r\\n", "Message Format"},
    {"DFM-LINE-004", L::kMust, N::kNothing,
     "Every device line is a reply of the protocol (hi, ms, mm, mp, sm, sa, jm, im, pr, zm, np, "
     "bf, go, or the sketch's two error lines): no stray output",
     "Messages are given from perspective of DFMoco device.",
     "Messages; docs/device-facts.md, DFMoco"},
    {"DFM-LINE-005", L::kMust, N::kNothing,
     "Apart from `mp` reports and the boot `hi`, every device line answers a command the host "
     "sent",
     "Any time a motor is moving, the device should send occasional \"mp\" messages.", "Notes"},
    {"DFM-LINE-006", L::kShould, N::kNothing,
     "Device lines are in the plain form of the examples: one space between fields, no leading or "
     "trailing space, decimals without sign or leading zeros",
     "EXAMPLE: hi 1 8 1.2.7", "Hello (hi)"},
    {"DFM-LINE-007", L::kNote, N::kNothing,
     "A command ended by a bare \"\\n\" is not taken (the sketch's framing), where ERRATA reads "
     "that it should be",
     "lines end with `\\r\\n`. Accept a bare `\\n` or `\\r` too.",
     "ERRATA 2.1; docs/device-facts.md, DFMoco"},

    // --- Hello ("Hello (hi) - initiate communication") ---
    {"DFM-HI-001", L::kShould, N::kNothing,
     "The device announces itself with `hi` unprompted when it starts",
     "At boot the sketch sends `hi <major> <axes> <version>` unprompted",
     "docs/device-facts.md, DFMoco"},
    {"DFM-HI-002", L::kMust, N::kNothing,
     "`hi` is answered with `hi <major version> <number of axes> <full version string>`",
     "OUT: hi <major version> <number of axes> <full version string>", "Hello (hi)"},
    {"DFM-HI-003", L::kMust, N::kNothing,
     "The major version is at least 1 and is the leading number of the full version string",
     "EXAMPLE: hi 1 8 1.2.7", "Hello (hi); ERRATA 2.2"},
    {"DFM-HI-004", L::kMust, N::kNothing, "The number of axes is at least 1",
     "Motor number starts at 1.", "Hello (hi)"},
    {"DFM-HI-005", L::kShould, N::kNothing,
     "The full version string is dotted decimal (major.minor.patch)", "EXAMPLE: hi 1 8 1.2.7",
     "Hello (hi)"},
    {"DFM-HI-006", L::kMust, N::kNothing,
     "Every `hi` the device sends (at boot and on request) is the same",
     "Hello (hi) - initiate communication", "Hello (hi)"},
    {"DFM-HI-007", L::kNote, N::kNothing,
     "The device is none of the known sketches (1.2.7, 1.3.0, 1.3.1, 2.0.0 with 4 or 8 axes)",
     "Version 1.x answers `hi 1 4 1.3.0` / `hi 1 4 1.2.7`. ... Uno drives 4 motors ...; Mega 8.",
     "docs/device-facts.md, DFMoco"},
    {"DFM-HI-008", L::kMust, N::kNothing,
     "The first `hi` a host sends is answered (not only a repeat after the host's timeout)",
     "Hello (hi) - initiate communication ... IN: hi OUT: hi <major version> <number of axes> "
     "<full version string>",
     "Hello (hi)"},

    // --- One reply per command ---
    {"DFM-REPLY-001", L::kMust, N::kNothing,
     "Every command that has an OUT line is answered (within the answer timeout)",
     "Messages are given from perspective of DFMoco device. IN: ... OUT: ...", "Messages"},
    {"DFM-REPLY-002", L::kMust, N::kNothing, "Every command is answered exactly once",
     "IN: sa OUT: sa", "Messages"},
    {"DFM-REPLY-003", L::kShould, N::kNothing,
     "A command word the device does not know gets no reply at all",
     "Unknown two-letter commands get no reply at all.", "docs/device-facts.md, DFMoco"},
    {"DFM-REPLY-004", L::kMust, N::kNothing,
     "Replies come in the order of the commands, also for commands sent back to back",
     "Outgoing messages wait in a 16-slot queue", "docs/device-facts.md, DFMoco"},
    {"DFM-REPLY-005", L::kMust, N::kNothing,
     "A reply to a motor command names the motor of the command",
     "OUT: sm <motor> ... OUT: jm <motor> ... OUT: pr <motor> <steps/second>", "Messages"},

    // --- Motor status ("Motor Status (ms)"; ERRATA 2.3) ---
    {"DFM-MS-001", L::kMust, N::kNothing,
     "`ms` is answered with `ms ` and one 0/1 digit per motor, no spaces",
     "OUT: ms <0 or 1 for each motor, 1 = moving>", "Motor Status (ms); ERRATA 2.3"},
    {"DFM-MS-002", L::kMust, N::kNothing,
     "The `ms` reply has exactly as many digits as the `hi` reply has axes",
     "`ms` -> `ms ` followed by one `0`/`1` digit per motor, no spaces.", "ERRATA 2.3"},
    {"DFM-MS-003", L::kMust, N::kMotors, "A motor's `ms` digit is 1 while it moves", "1 = moving",
     "Motor Status (ms)"},
    {"DFM-MS-004", L::kMust, N::kMotors, "Every `ms` digit is 0 once every motor has come to rest",
     "Dragonframe will keep requesting motor status (ms) until the movement is finished.", "Notes"},

    // --- Move motor ("Move Motor (mm)"; ERRATA 2.4) ---
    {"DFM-MM-001", L::kMust, N::kMotors,
     "`mm m p` to a position the motor is not at is answered `mm m p` with the target",
     "EXAMPLE: mm 1 250 (if motor needs to move)", "Move Motor (mm)"},
    {"DFM-MM-002", L::kMust, N::kMotors,
     "`mm m p` to the position a resting motor is at is answered `mp m p`",
     "EXAMPLE: mp 1 250 (if motor was already there)", "Move Motor (mm); ERRATA 2.4"},
    {"DFM-MM-003", L::kMust, N::kMotors, "After `mm m p` the motor comes to rest on p",
     "Move Motor (mm) - move a motor to a position", "Move Motor (mm)"},

    // --- Motor position ("Motor Position Query (mp)", "Notes") ---
    {"DFM-MP-001", L::kMust, N::kMotors,
     "`mp m` is answered `mp m pos` with the position of the resting motor",
     "OUT: mp <motor> <step position>", "Motor Position Query (mp)"},
    {"DFM-MP-002", L::kShould, N::kMotors,
     "A motor that moves for more than 1.5 s is reported by unprompted `mp` lines while it moves",
     "Any time a motor is moving, the device should send occasional \"mp\" messages.", "Notes"},
    {"DFM-MP-003", L::kShould, N::kMotors,
     "While a motor moves, its `mp` reports are at most 1 s apart (+ the reply deadline)",
     "While moving, `mp m pos` goes out once per second per moving motor",
     "docs/device-facts.md, DFMoco"},
    {"DFM-MP-004", L::kShould, N::kMotors,
     "An `mp` report follows a motor's stop within 1 s (+ the reply deadline)",
     "plus once after the motor stops (so the last one can lag the stop by up to 1 s)",
     "docs/device-facts.md, DFMoco"},
    {"DFM-MP-005", L::kMust, N::kMotors,
     "An `mp` the device sends after a motor stopped carries the position the motor rests at",
     "OUT: mp <motor> <step position>", "Motor Position Query (mp); Notes"},
    {"DFM-MP-006", L::kMust, N::kMotors,
     "`mp` reports of a moving motor lie between where the move started and its target",
     "Any time a motor is moving, the device should send occasional \"mp\" messages.", "Notes"},
    {"DFM-MP-007", L::kShould, N::kNothing,
     "Nothing is sent unprompted while every motor rests and no stop is still to be reported",
     "While moving, `mp m pos` goes out once per second per moving motor, plus once after the "
     "motor stops",
     "docs/device-facts.md, DFMoco"},

    // --- New position / zero ("New Position (np)", "Zero Motor (zm)") ---
    {"DFM-NP-001", L::kMust, N::kMotors,
     "`np m p` is answered `mp m p` (the sketch) or `np m p` (protocol text)",
     "OUT: np <motor> <position>", "New Position (np); docs/device-facts.md, DFMoco"},
    {"DFM-NP-002", L::kMust, N::kMotors, "`np m p` moves nothing and the motor then reports p",
     "sets the motor's current position to a new value (no movement)", "New Position (np)"},
    {"DFM-NP-003", L::kNote, N::kMotors,
     "`np` is answered `np m p` as the protocol text says, where the sketch answers `mp m p`",
     "`np m p` -> `mp m p` (not `np` as the protocol text says).", "docs/device-facts.md, DFMoco"},
    {"DFM-ZM-001", L::kMust, N::kMotors,
     "`zm m` is answered `mp m 0` (the sketch) or `zm m` (protocol text)", "OUT: zm <motor>",
     "Zero Motor (zm); docs/device-facts.md, DFMoco"},
    {"DFM-ZM-002", L::kMust, N::kMotors, "`zm m` moves nothing and the motor then reports 0",
     "resets the motor's current position to zero (no movement)", "Zero Motor (zm)"},
    {"DFM-ZM-003", L::kNote, N::kMotors,
     "`zm` is answered `zm m` as the protocol text says, where the sketch answers `mp m 0`",
     "`zm m` -> `mp m 0`, sent twice.", "docs/device-facts.md, DFMoco"},

    // --- Stopping ("Stop Motor (sm)", "Stop All (sa)") ---
    {"DFM-SM-001", L::kMust, N::kMotors, "`sm m` is answered `sm m`", "OUT: sm <motor>",
     "Stop Motor (sm)"},
    {"DFM-SM-002", L::kMust, N::kMotors,
     "After `sm m` the moving motor comes to rest short of its target within 5 s",
     "Stop Motor (sm) - stop a motor fairly quickly", "Stop Motor (sm)"},
    {"DFM-SM-003", L::kMust, N::kTwoMotors, "`sm m` leaves the other motors moving",
     "Stop Motor (sm) - stop a motor fairly quickly", "Stop Motor (sm)"},
    {"DFM-SA-001", L::kMust, N::kNothing, "`sa` is answered `sa`", "IN: sa OUT: sa",
     "Stop All (sa)"},
    {"DFM-SA-002", L::kMust, N::kMotors,
     "After `sa` every moving motor comes to rest short of its target within 5 s",
     "Stop All (sa) - stop all motors fairly quickly", "Stop All (sa)"},

    // --- Pulse rate ("Pulse Rate (pr)") ---
    {"DFM-PR-001", L::kMust, N::kMotors, "`pr m v` with v in 100..20000 is answered `pr m v`",
     "OUT: pr <motor> <steps/second>", "Pulse Rate (pr)"},
    {"DFM-PR-002", L::kShould, N::kMotors,
     "A pulse rate outside 100..20000 is clamped, and the answer shows the clamped rate",
     "`pr m v` -> `pr m v`, v clamped to 100..20000 steps/s", "docs/device-facts.md, DFMoco"},
    {"DFM-PR-003", L::kMust, N::kMotors,
     "A motor never moves faster than its pulse rate (a move of d steps at rate v takes at least "
     "d/v)",
     "Pulse Rate (pr) - set the maximum steps/second of motor", "Pulse Rate (pr)"},

    // --- Jog and inch ("Jog Motor (jm)", "Inch Motor (im)") ---
    {"DFM-JM-001", L::kMust, N::kMotors, "`jm m dest` is answered `jm m`", "OUT: jm <motor>",
     "Jog Motor (jm)"},
    {"DFM-JM-002", L::kMust, N::kMotors,
     "A jog moves the motor towards its destination and never past it",
     "move the motor at a reasonable speed (pulse rate) towards destination", "Jog Motor (jm)"},
    {"DFM-JM-003", L::kMust, N::kJogVelocity,
     "With major version 2 or greater, `jm m dest velocity` is accepted (`jm m`) and moves "
     "towards dest",
     "velocity will be passed as a third argument if the major version in the hi response is 2 "
     "or greater.",
     "Jog Motor (jm); ERRATA 2.2"},
    {"DFM-IM-001", L::kMust, N::kMotors, "`im m dest` is answered `im m`", "OUT: im <motor>",
     "Inch Motor (im)"},
    {"DFM-IM-002", L::kMust, N::kMotors,
     "An inch from rest moves the motor towards its destination by at least one step, at most "
     "one step past it",
     "move the in very small increments towards destination",
     "Inch Motor (im); docs/device-facts.md, DFMoco"},
    {"DFM-IM-003", L::kShould, N::kMotors, "One inch moves the motor 16 steps at most",
     "move the in very small increments towards destination",
     "Inch Motor (im); docs/device-facts.md, DFMoco"},

    // --- Errors (the protocol text has none; FACTS) ---
    {"DFM-ERR-001", L::kShould, N::kNothing,
     "A known command with a wrong argument count or a malformed number is answered `parse "
     "error`",
     "A wrong argument count, an invalid motor, or `bf`/`go` while a motor moves answer `parse "
     "error`.",
     "docs/device-facts.md, DFMoco"},
    {"DFM-ERR-002", L::kShould, N::kMotors,
     "A motor number of 0 or above the number of axes is answered `parse error`",
     "A wrong argument count, an invalid motor, or `bf`/`go` while a motor moves answer `parse "
     "error`.",
     "docs/device-facts.md, DFMoco"},
    {"DFM-ERR-003", L::kShould, N::kNothing,
     "A command with 40 or more arguments is answered `error: too many args`",
     "40 or more arguments answer `error: too many args`.", "docs/device-facts.md, DFMoco"},
    {"DFM-ERR-004", L::kMust, N::kMotors,
     "A command the device refuses moves nothing and changes no position",
     "Motor number starts at 1.", "Messages; docs/device-facts.md, DFMoco"},
    {"DFM-ERR-005", L::kMust, N::kNothing,
     "After a refused or unknown command the next valid command is answered normally",
     "Messages are in ASCII text, with trailing \\r\\n", "Message Format"},

    // --- Go-motion ("Go-Motion (Blur)"; ERRATA 2.5) ---
    {"DFM-GO-001", L::kMust, N::kGoMotion,
     "`bf ...` is answered with one `bf <n>` line: n = 1000, the exposure time, or -1 (refused)",
     "OUT: bf 1000", "Go-Motion (Blur); ERRATA 2.5; docs/device-facts.md, DFMoco"},
    {"DFM-GO-002", L::kNote, N::kGoMotion,
     "`bf` answers 1000 for an exposure other than 1000 ms (the sketch), where ERRATA reads the "
     "number as an echo of the exposure time",
     "`bf ...` reply: the document's example `bf 1000` is ambiguous; take it as an echo of the "
     "exposure time.",
     "ERRATA 2.5; docs/device-facts.md, DFMoco"},
    {"DFM-GO-003", L::kMust, N::kGoMotion,
     "After an accepted `bf` the motors move to the start of the 1 s ramp before the exposure "
     "(within 2 steps) and rest there",
     "After the device calculates the go-motion move, it starts sending all motors into the "
     "initial position.",
     "Go-Motion (Blur); docs/device-facts.md, DFMoco"},
    {"DFM-GO-004", L::kMust, N::kGoMotion, "`go` is answered `go`", "IN: go OUT: go",
     "Go-Motion (Blur)"},
    {"DFM-GO-005", L::kMust, N::kGoMotion,
     "After `go` each motor runs through the exposure and rests at the end of the 1 s ramp after "
     "it (within 2 steps)",
     "At this point the rig should immediately start the go-motion move as described above.",
     "Go-Motion (Blur); docs/device-facts.md, DFMoco"},
    {"DFM-GO-006", L::kShould, N::kGoMotion,
     "The go-motion move runs the 1 s ramp, the exposure (half its time on each half) and the 1 s "
     "slow-down: it lasts their sum, and the motors are where that plan puts them, both within "
     "150 ms",
     "The ramp up to speed should take exactly 1 second, even if the device does not need to "
     "move.",
     "Go-Motion (Blur); ERRATA 2.5; docs/device-facts.md, DFMoco"},
    {"DFM-GO-007", L::kShould, N::kGoMotion,
     "`bf` while a motor moves is refused with `parse error`",
     "`bf exp blur {ch p0 p1 p2}...` is refused while moving.", "docs/device-facts.md, DFMoco"},
    {"DFM-GO-008", L::kMust, N::kBlurRefusal,
     "A `bf` whose speed would exceed 20000 steps/s is answered `bf -1` and moves nothing",
     "reply `bf 1000`, or `bf -1` (1.3.1 and later) if a speed would exceed 20000.",
     "docs/device-facts.md, DFMoco"},

    // --- Reply deadlines (runner options; the protocol gives no number) ---
    {"DFM-DL-001", L::kShould, N::kNothing,
     "`hi` is answered within the deadline (--deadline-ms, default 250 ms)",
     "Hello (hi) - initiate communication", "Hello (hi)"},
    {"DFM-DL-002", L::kShould, N::kNothing,
     "Queries (`ms`, `mp m`) are answered within the deadline",
     "Dragonframe will keep requesting motor status (ms) until the movement is finished.", "Notes"},
    {"DFM-DL-003", L::kShould, N::kNothing,
     "Motor commands (mm, sm, sa, jm, im, pr, zm, np) are answered within the deadline",
     "Messages are given from perspective of DFMoco device.", "Messages"},
    {"DFM-DL-004", L::kShould, N::kGoMotion,
     "`bf` and `go` are answered within the deadline (kind rt)",
     "At this point the rig should immediately start the go-motion move", "Go-Motion (Blur)"},

    // --- Motors ---
    {"DFM-MOTOR-001", L::kMust, N::kNothing,
     "Every motor number in a device line is 1 to the number of axes", "Motor number starts at 1.",
     "Messages"},
    {"DFM-MOTOR-002", L::kMust, N::kTwoMotors,
     "A command to one motor leaves every other motor where it is",
     "IN: mm <motor> <step position>", "Move Motor (mm)"},

    // --- The outgoing queue ---
    {"DFM-QUEUE-001", L::kShould, N::kNothing,
     "Twelve commands sent in one write are all answered, in order",
     "Outgoing messages wait in a 16-slot queue that drops silently on overflow",
     "docs/device-facts.md, DFMoco"},

    // --- The StackShot 3X DfMoco dialect (stackshot-protocol.txt section 3;
    // ERRATA 3.9): judged only when the device is judged in that dialect
    // (--dialect stackshot3x, or auto and `hi 1 3 1.2.6`) ---
    {"DFM-SS-001", L::kMust, N::kNothing, "StackShot 3X dialect: `hi` advertises 1 to 3 axes",
     "Up to three axes can be controlled. ... Motors are specified as 1, 2, or 3.",
     "stackshot-protocol.txt 3; ERRATA 3.9"},
    {"DFM-SS-002", L::kMust, N::kMotors,
     "StackShot 3X dialect: `mm m p` to a position the motor is not at is answered `mm m <current "
     "position>` (where "
     "the motor is, not p)",
     "If NOT at the specified position, this will be transmitted periodically: rsp: mm <motor> "
     "<current position>",
     "stackshot-protocol.txt 3"},
    {"DFM-SS-003", L::kShould, N::kMotors,
     "StackShot 3X dialect: A motor that moves for more than 1.5 s is reported by unprompted `mm m "
     "<current position>` "
     "lines, each between where the move started and its target",
     "If NOT at the specified position, this will be transmitted periodically: rsp: mm <motor> "
     "<current position>",
     "stackshot-protocol.txt 3"},
    {"DFM-SS-004", L::kMust, N::kMotors,
     "StackShot 3X dialect: `mp *` is answered with one `mp m pos` line per motor, 1 to the axes "
     "in order, each the "
     "motor's position",
     "Optionally, a \"*\" can be sent as the motor to have all positions sent.",
     "stackshot-protocol.txt 3"},
    {"DFM-SS-005", L::kMust, N::kMotors,
     "StackShot 3X dialect: `zm m` and `np m p` are answered `mp m <current position>` (0 after "
     "`zm`, p after `np` at "
     "rest), not `zm`/`np`",
     "cmd: zm <motor> rsp: mp <motor> <current position> ... cmd: np <motor> <position> rsp: mp "
     "<motor> <current position> (yes, that is a \"m\")",
     "stackshot-protocol.txt 3; ERRATA 3.9"},
    {"DFM-SS-006", L::kShould, N::kMotors,
     "StackShot 3X dialect: `np m p` while the motor moves sends it to p: it comes to rest on p",
     "Set a new target position. If the motor is currently moving it will go to that position.",
     "stackshot-protocol.txt 3"},
    {"DFM-SS-007", L::kMust, N::kMotors,
     "StackShot 3X dialect: `sa <motor>` is answered `sa` and every moving motor comes to rest "
     "short of its target "
     "within 5 s",
     "cmd: sa <motor> rsp: sa Stop All.", "stackshot-protocol.txt 3"},
    {"DFM-SS-008", L::kMust, N::kMotors,
     "StackShot 3X dialect: `pr m v` is answered `pr m v` up to the controller's maximum and `pr m "
     "<maximum>` (below v) "
     "above it",
     "If the requested speed is faster than the controller is allowing, then the controller will "
     "respond with the maximum speed.",
     "stackshot-protocol.txt 3"},
    {"DFM-SS-009", L::kShould, N::kMotors,
     "StackShot 3X dialect: `bf` and `go` get no go-motion answer (`bf`, `go`) and move nothing",
     "The DfMoco interface does not support real-time motion control. It can only be used for "
     "shoot-move-shoot applications.",
     "stackshot-protocol.txt 3"},
};

}  // namespace

const std::vector<Rule>& DfmocoRules() {
  static const std::vector<Rule> kAll = [] {
    std::vector<Rule> all = kRules;
    all.insert(all.end(), DfmocoPinRules().begin(), DfmocoPinRules().end());
    return all;
  }();
  return kAll;
}

}  // namespace moco::conformance
