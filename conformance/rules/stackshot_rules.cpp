// The StackShot 3X rule catalogue (stackshot-protocol.txt sections 1.1-2;
// ERRATA stackshot 1-10; FACTS "StackShot"): packets, checksums, one reply
// per request, status codes, reply layouts, identity, NVM and the write-once
// serial number, motion, configuration, stacks, Bezier curves and deadlines.
// Clauses are quoted from the spec; where it is silent, garbled or
// self-contradictory the ERRATA or FACTS reading is quoted and named.
#include "conformance/rules/catalogue.h"
#include "conformance/rules/stackshot_needs.h"

namespace moco::conformance {
namespace {

using L = Level;
using N = StackshotNeeds;

const std::vector<Rule> kStackshotRules = {
    // --- Packets (section 2; ERRATA 1, 3, 6) ---
    {"SS-PKT-001", L::kMust, N::kNothing,
     "Every device byte belongs to a packet that starts with the device sync byte 0xAA",
     "Sync 0x55 (PC) 0xAA (Slave) | CMD MSB | CMD LSB | Action/Status | Data Length | Data[0..n] | "
     "Checksum",
     "2 Serial Communications Interface; ERRATA 1"},
    {"SS-PKT-002", L::kMust, N::kNothing,
     "The device never leaves a packet unfinished (Data Length data bytes and the checksum follow)",
     "Length specifies the length of the data field.", "2 Serial Communications Interface"},
    {"SS-PKT-003", L::kMust, N::kNothing,
     "A reply's status (low nibble of the action/status byte) is a response code: RSP_OK, "
     "BAD_PARAM, UNSUPPORTED_ACTION, UNSUPPORTED_CMD, FAILED, NOT_EMPTY or BUSY",
     "Responses use COMM_ACTION_RSP_OK / BAD_PARAM / UNSUPPORTED_* / FAILED / NOT_EMPTY / BUSY in "
     "the low nibble.",
     "1.2 comm_action_t; ERRATA 3"},
    {"SS-PKT-004", L::kShould, N::kNothing,
     "A reply carries the request's upper nibble (axis in bits 4-5, sub-item in bit 7)",
     "When parsing the response for the 3-axis controller, be sure to mask off the upper-nibble of "
     "the Action/Status if investigating the response.",
     "2 Serial Communications Interface; ERRATA 3"},
    {"SS-PKT-005", L::kMust, N::kNothing,
     "A request delivered one byte at a time (without a 2 ms pause) is answered as a whole one",
     "One frame consists of a host command transmit and a slave response.",
     "2 Serial Communications Interface"},
    {"SS-PKT-006", L::kMust, N::kNothing,
     "After a partial packet and the 2 ms inter-frame gap, the next packet is answered",
     "Mandatory 2ms inter-frame delay for re-syncing to recover from partial packet transmission.",
     "2 Serial Communications Interface; ERRATA 6"},

    // --- Checksum (ERRATA 2; FACTS) ---
    {"SS-CSUM-001", L::kNote, N::kNothing,
     "The device's checksum byte is not the negated 8-bit sum of the bytes after sync (the "
     "reading taken)",
     "The checksum algorithm is not given (\"sent but not currently verified\") ... Pick one "
     "documented algorithm for what the emulator sends (e.g. the 8-bit sum of all bytes after "
     "sync, negated)",
     "ERRATA 2"},
    {"SS-CSUM-002", L::kShould, N::kNothing,
     "Every device packet's checksum follows one documented algorithm throughout (negated sum, "
     "constant 0x69 or constant 0x00)",
     "No known host computes the trailing checksum: published tools send a constant (0x69 in one "
     "Python/C++ family, 0x00 in a Java tool).",
     "ERRATA 2; docs/device-facts.md, StackShot"},
    {"SS-CSUM-003", L::kMust, N::kNothing,
     "A request is answered whatever its checksum byte (computed, 0x69, 0x00 or wrong)",
     "A device must therefore not reject packets for their checksum byte.",
     "docs/device-facts.md, StackShot; ERRATA 2"},

    // --- One reply per request (section 2) ---
    {"SS-ANS-001", L::kMust, N::kNothing,
     "Every request is answered (within the answer timeout, --answer-timeout-ms)",
     "One frame consists of a host command transmit and a slave response.",
     "2 Serial Communications Interface"},
    {"SS-ANS-002", L::kMust, N::kNothing,
     "Every request is answered exactly once; the device sends nothing unasked",
     "One frame consists of a host command transmit and a slave response.",
     "2 Serial Communications Interface"},
    {"SS-ANS-003", L::kMust, N::kNothing,
     "A reply carries the command id of the request it answers",
     "Example: Reading the current position has a command ID of 0x1002.",
     "2 Serial Communications Interface; ERRATA 1"},

    // --- Status codes (1.2 comm_action_t) ---
    {"SS-CODE-001", L::kMust, N::kNothing,
     "A known command with an action it allows is never answered UNSUPPORTED_CMD or "
     "UNSUPPORTED_ACTION (unimplemented NAND/NOR/WIFI/WAD excepted)",
     "COMM_ACTION_UNSUPPORTED_ACTION, // The action specified is invalid; "
     "COMM_ACTION_UNSUPPORTED_CMD, // The command passed in is invalid",
     "1.2 comm_action_t"},
    {"SS-CODE-002", L::kShould, N::kNothing,
     "BUSY answers only writes, NOT_EMPTY only a write to the write-once serial number",
     "COMM_ACTION_NOT_EMPTY, // The write operation was to a write-once register and it is no "
     "longer empty; COMM_ACTION_BUSY, // The controller is already performing the specified action",
     "1.2 comm_action_t"},
    {"SS-CODE-003", L::kMust, N::kNothing,
     "A valid request the device can carry out is answered RSP_OK",
     "COMM_ACTION_RSP_OK, // Controller responded with OK", "1.2 comm_action_t"},

    // --- Reply layouts (section 2 tables; ERRATA 4) ---
    {"SS-LAYOUT-001", L::kMust, N::kNothing,
     "An RSP_OK reply to a READ has the command's read-response layout (e.g. STATUS 4 bytes, "
     "POSITION units + f32 = 5, NUM_STEPS 2, PING 2, strings NUL-terminated)",
     "CC_RAIL_POSITION_TARGET response is units (u8) + f32 = 5 bytes (not 6); "
     "CC_RAIL_CONFIG_NUM_STEPS is a u16 (2 bytes, not 1).",
     "2 (each command's Rsp Data); ERRATA 4"},
    {"SS-LAYOUT-002", L::kMust, N::kNothing, "An RSP_OK reply to a WRITE carries no data",
     "Rsp Data: <none>", "2 (each command's Write table)"},
    {"SS-LAYOUT-003", L::kShould, N::kNothing, "An error reply carries no data",
     "A length of zero would result in a packet of Sync, command (2), Length, and Checksum",
     "2 Serial Communications Interface"},
    {"SS-LAYOUT-004", L::kMust, N::kNothing,
     "A units + f32 reply names the units the request asked for",
     "0 comm_rail_units_t Units that the data represents", "2 CC_RAIL_POSITION_CURRENT"},

    // --- Errors ---
    {"SS-ERR-001", L::kMust, N::kNothing, "An unknown command id is answered UNSUPPORTED_CMD",
     "COMM_ACTION_UNSUPPORTED_CMD, // The command passed in is invalid", "1.2 comm_action_t"},
    {"SS-ERR-002", L::kMust, N::kNothing,
     "An action a command does not allow (a READ of a write-only command, a WRITE of a read-only "
     "one, a response code from the host) is answered UNSUPPORTED_ACTION",
     "COMM_ACTION_UNSUPPORTED_ACTION, // The action specified is invalid",
     "1.2 comm_action_t; 2 (Action: Read only / Write only)"},
    {"SS-ERR-003", L::kMust, N::kNothing,
     "A known command whose data length fits no layout is refused (never RSP_OK)",
     "COMM_ACTION_BAD_PARAM, // A bad parameter was passed to the controller", "1.2 comm_action_t"},
    {"SS-ERR-004", L::kNote, N::kNothing, "CC_WAD is answered other than UNSUPPORTED_CMD",
     "CC_WAD (0x1200, composite message) has no documented layout: answer it with "
     "COMM_ACTION_UNSUPPORTED_CMD unless a layout is defined later.",
     "ERRATA 10"},
    {"SS-ERR-005", L::kShould, N::kNothing,
     "An axis-addressed command for axis 3 (bits 4-5 = 11, no such axis) is refused BAD_PARAM",
     "If the command applies to an axis or shutter output, it is \"or'ed\" into bits 4,5",
     "2 Serial Communications Interface; ERRATA 3"},

    // --- CC_PING ---
    {"SS-PING-001", L::kMust, N::kNothing,
     "CC_PING answers the value sent XOR 0xFF and a reserved zero byte",
     "\"Exclusive or\" response to value sent to controller above: out = in ^ 0xFF; "
     "<reserved, currently set to zero>",
     "2 CC_PING"},
    {"SS-PING-002", L::kNote, N::kNothing,
     "A ping at CC_PING's table id 0x110A is not answered as a ping (the device numbers CC_PING "
     "0x110B only)",
     "CC_PING ID: 0x110A", "2 CC_PING; wire/stackshot_constants.h reading"},

    // --- Identity (1.1.10-1.1.14) ---
    {"SS-ID-001", L::kMust, N::kNothing, "CC_SOFTWARE_STRING is NUL-terminated text",
     "Null-terminated string containing the current software version string.",
     "2 CC_SOFTWARE_STRING"},
    {"SS-ID-002", L::kShould, N::kNothing,
     "The software, hardware and bootloader ids and the software string are the same each time",
     "Each hardware revision has a unique identifier associated with it.",
     "1.1.12 StackShot_GetHardwareID"},

    // --- Serial number (1.1.15-1.1.16; CC_SERIAL_NUMBER) ---
    {"SS-SERIAL-001", L::kMust, N::kNothing,
     "A write to a programmed serial number is refused and the number stays as it was",
     "This is a one-time programmable burn. Once the serial number is set it cannot be erased or "
     "reprogrammed. Returns COMM_ACTION_FAILED if a second write is attempted.",
     "2 CC_SERIAL_NUMBER; 1.1.16"},
    {"SS-SERIAL-002", L::kNote, N::kNothing,
     "A second serial-number write is refused NOT_EMPTY (section 1.1.16) instead of FAILED (the "
     "CC_SERIAL_NUMBER table)",
     "COMM_STATUS_NOT_EMPTY The serial number was not stored because one is already saved.",
     "1.1.16 StackShot_SetSerialNumber"},
    {"SS-SERIAL-003", L::kMust, N::kNothing,
     "The serial number survives a CC_RESET and a power cycle",
     "Store the specified serial number into the StackShot device. This is a write-once register.",
     "1.1.16 StackShot_SetSerialNumber"},
    {"SS-SERIAL-004", L::kMust, N::kNothing,
     "The first write to an unprogrammed (0xFFFFFFFF) serial number is stored and read back",
     "A value of 0xFFFFFFF represents an unprogrammed serial number.",
     "1.1.15 StackShot_GetSerialNumber; 2 CC_SERIAL_NUMBER"},

    // --- NVM registers (1.1.17-1.1.18; CC_NVM_ACCESS) ---
    {"SS-NVM-001", L::kMust, N::kNothing, "A value written to an NVM register (1-31) reads back",
     "32-bit value to store to NVM (re-writes are possible).", "2 CC_NVM_ACCESS"},
    {"SS-NVM-002", L::kMust, N::kNothing,
     "A register beyond the device's range (>= 128) is refused BAD_PARAM",
     "COMM STATUS BAD PARAM The \"reg\" value is outside of the allowed range.",
     "1.1.17 StackShot_GetNVMRegister; 1.1.18"},
    {"SS-NVM-003", L::kMust, N::kNothing, "NVM registers survive a CC_RESET and a power cycle",
     "Store a 32-bit non-volatile value to StackShot.", "1.1.18 StackShot_SetNVMRegister"},
    {"SS-NVM-004", L::kShould, N::kNothing,
     "NVM register 0 and CC_RAIL_CONFIG_AXIS hold the same axis identifier",
     "Register \"0\" maps to the axis definition for the device", "1.1.17; 2 CC_RAIL_CONFIG_AXIS"},
    {"SS-NVM-005", L::kNote, N::kNothing,
     "Registers 32-127 are refused (the device follows the API's 0-31, not the table's 0-127)",
     "reg The register to read. Valid values are 0-31. / Indicates which NVM register (0-127) that "
     "is desired",
     "1.1.17 vs 2 CC_NVM_ACCESS"},

    // --- CC_RAIL_STATUS (1.1.6) ---
    {"SS-STATUS-001", L::kMust, N::kNothing,
     "CC_RAIL_STATUS sets no bits besides MOVING 0x01, SHUTTER 0x02 and USER_ABORTED 0x04",
     "RAIL_STATUS_IDLE 0000 Rail Idle RAIL_STATUS_MOVING 0001 Rail moving RAIL_STATUS_SHUTTER 0002 "
     "Shutter firing RAIL_STATUS_USER_ABORTED 0004 User aborted during a move",
     "2 CC_RAIL_STATUS"},
    {"SS-STATUS-002", L::kMust, N::kNothing,
     "MOVING is set while the rail moves and clears once it comes to rest",
     "#define RAIL_STATUS_MOVING 0x01 The rail is currently moving.", "1.1.6 StackShot_GetStatus"},
    {"SS-STATUS-003", L::kMust, N::kNothing, "A rail at rest reports no MOVING bit",
     "#define RAIL_STATUS_IDLE 0x00 The rail is idle.", "1.1.6 StackShot_GetStatus"},
    {"SS-STATUS-004", L::kMust, N::kNothing,
     "SHUTTER is set while the shutter output fires and clears after its last pulse",
     "#define RAIL_STATUS_SHUTTER 0x02 The shutter is currently firing.",
     "1.1.6; 1.1.5 StackShot_ShutterFire"},
    {"SS-STATUS-005", L::kMust, N::kNothing,
     "USER_ABORTED appears only after a button abort, is reported by the next STATUS read and is "
     "cleared by it (sticky)",
     "Note: The RAIL STATUS USER ABORTED bit will clear once read (sticky).",
     "1.1.6 StackShot_GetStatus"},

    // --- Positions (1.1.8-1.1.9) ---
    {"SS-POS-001", L::kMust, N::kNothing,
     "CC_RAIL_POSITION_ZERO at rest sets current and target position to 0 without moving",
     "This does not move the rail, it simply sets the internal position (both current and target) "
     "to zero.",
     "1.1.9 StackShot_ZeroPosition"},
    {"SS-POS-002", L::kMust, N::kNothing,
     "CC_RAIL_POSITION_ZERO while the rail moves is refused BUSY",
     "This command will be rejected with COMM_STATUS_BUSY if the motor is moving.",
     "2 CC_RAIL_POSITION_ZERO"},
    {"SS-POS-003", L::kMust, N::kNothing,
     "One position read in mils and in mm agrees (1 mil = 0.0254 mm)",
     "COMM RAIL UNITS ENGLISH \"distance\" specifies mils. (1.0 represents one thousandth of an "
     "inch)",
     "1.1.8 StackShot_GetCurrentPosition"},
    {"SS-POS-004", L::kMust, N::kNothing, "At rest the target position equals the current position",
     "Absolute target position in the specified units above that represents the target position "
     "of the rail.",
     "2 CC_RAIL_POSITION_TARGET"},

    // --- Moves (1.1.3-1.1.4) ---
    {"SS-MOVE-001", L::kMust, N::kNothing,
     "CC_RAIL_MOVE at rest is accepted and the rail comes to rest the distance away; back-to-back "
     "moves add up",
     "The move command is relative from the target position of the rail. If two move commands of "
     "10.0 mm are issued back to back, the rail will move 20.0 mm total.",
     "1.1.3 StackShot_Move"},
    {"SS-MOVE-002", L::kMust, N::kNothing,
     "CC_RAIL_MOVE while the rail moves is either refused BUSY, the move under way unchanged, or "
     "accepted and added to the target; nothing else",
     "The move command is relative from the target position of the rail. If two move commands of "
     "10.0 mm are issued back to back, the rail will move 20.0 mm total. ... COMM_STATUS_BUSY "
     "StackShot is currently moving. The move request was rejected.",
     "1.1.3 StackShot_Move"},
    {"SS-MOVE-003", L::kMust, N::kNothing,
     "CC_RAIL_MOVE_AT_SPEED moves the distance from the rail's immediate position",
     "This move command is relative from the rail's immediate position.",
     "1.1.4 StackShot_MoveAtSpeed"},
    {"SS-MOVE-004", L::kShould, N::kNothing,
     "CC_RAIL_MOVE_AT_SPEED while the rail moves is accepted (its return values list no BUSY)",
     "the rail will move 10.0 mm from the position where the rail is upon receiving the second "
     "command.",
     "1.1.4 StackShot_MoveAtSpeed"},
    {"SS-MOVE-005", L::kMust, N::kNothing,
     "A move with a bad direction, units or speed fraction is refused BAD_PARAM and the rail stays",
     "COMM_STATUS_BAD_PARAM One of the parameters specified is not a valid value.", "1.1.3; 1.1.4"},
    {"SS-MOVE-006", L::kNote, N::kNothing,
     "A negative distance is accepted (the reading taken: the direction byte carries the sign, a "
     "negative distance is BAD_PARAM)",
     "direction Direction to move the rail. Valid values are: COMM_RAIL_DIR_FWD ... "
     "COMM_RAIL_DIR_BACK",
     "1.1.3 StackShot_Move"},
    {"SS-MOVE-007", L::kNote, N::kNothing,
     "CC_RAIL_MOVE while the rail moves is refused BUSY (the reading taken: the return value's), "
     "not added to the target (the summary's back-to-back reading)",
     "COMM_STATUS_BUSY StackShot is currently moving. The move request was rejected.",
     "1.1.3 StackShot_Move"},
    {"SS-STOP-001", L::kMust, N::kNothing,
     "CC_RAIL_STOP during a long move is accepted and the rail comes to rest short of its target",
     "Stop StackShot from moving. ... COMM STATUS SUCCESS The rail was stopped.",
     "1.1.7 StackShot_Stop"},
    {"SS-STOP-002", L::kMust, N::kNothing, "CC_RAIL_STOP at rest is accepted and moves nothing",
     "COMM STATUS SUCCESS The rail was stopped.", "1.1.7 StackShot_Stop"},
    {"SS-SHUT-001", L::kMust, N::kNothing,
     "CC_RAIL_SHUTTER_FIRE is accepted (out-of-range values bounded, not refused)",
     "If a parameter is out of bounds it will be bounded to the minimum/maximum allowed. ... "
     "COMM_STATUS_SUCCESS The shutter trigger output is activated.",
     "1.1.5 StackShot_ShutterFire"},

    // --- Stacks (CC_RAIL_STACK, StackShot 3X) ---
    {"SS-STACK-001", L::kMust, N::kThreeAxes,
     "CC_RAIL_STACK at rest is accepted, STACK_STATUS shows it running, STACK_POSITION counts up "
     "to the number of steps and the stack ends; the shutter fires (CC_RAIL_STATUS SHUTTER) in "
     "each frame and the rail ends on the end position (auto-return off)",
     "Run a 1 - 3 axis stack using the passed in parameters; Get the current status of a running "
     "stack; Get the current position of a stack / Time in seconds the rail should pause before "
     "activating the shutter. / Number of pulses (pictures to be taken) applied at each step.",
     "1.2 comm_cmd_t; 2 CC_RAIL_STACK, CC_RAIL_CONFIG_SETTLE_TIME, CC_RAIL_CONFIG_NUM_PULSES"},
    {"SS-STACK-002", L::kMust, N::kThreeAxes, "CC_RAIL_STACK while an axis moves is refused BUSY",
     "COMM_ACTION_BUSY, // The controller is already performing the specified action",
     "2 CC_RAIL_STACK; 1.2 comm_action_t"},

    // --- Configuration (CC_RAIL_CONFIG_*) ---
    {"SS-CFG-001", L::kMust, N::kNothing, "A configuration value written within range reads back",
     "Action: Read/Write", "2 CC_RAIL_CONFIG_*"},
    {"SS-CFG-002", L::kMust, N::kNothing,
     "Out-of-range configuration values (backlight/torque outside 1-10, holding torque above 10, "
     "units, mode, global mode and shutter beyond their enums) are refused BAD_PARAM and change "
     "nothing",
     "Backlighting level. Valid values are 1-10. / Torque setting. Valid values are 1-10. / "
     "Holding torque setting. Valid values are 0-10.",
     "2 CC_RAIL_CONFIG_BACKLIGHT, _TORQUE, _HOLDING_TORQUE; 1.2 enums"},
    {"SS-CFG-003", L::kMust, N::kNothing,
     "A units + f32 setting written in one unit reads back the same in that unit and converted in "
     "another",
     "0 comm_rail_units_t Units that the data represents. 1-4 F32 Distance in the specified units "
     "above",
     "2 CC_RAIL_CONFIG_BACKLASH, _SPEED, _TOTAL_DISTANCE"},
    {"SS-CFG-004", L::kShould, N::kNothing,
     "Negative or non-finite distances, speeds and times are refused BAD_PARAM",
     "Duration of shutter pulse (non-zero, non-negative).", "2 CC_RAIL_SHUTTER_FIRE (by analogy)"},
    {"SS-CFG-005", L::kMust, N::kNothing,
     "CC_RAIL_CONFIG_NAME reads back the name written, NUL-terminated",
     "Null-terminated string for the current configuration.", "2 CC_RAIL_CONFIG_NAME"},
    {"SS-SLOT-001", L::kMust, N::kNothing,
     "A configuration saved to a user slot (1-10) comes back with CC_RAIL_CONFIG_LOAD",
     "1-10 – Store the active configuration in the specified user slot. / 1-10 – Load the active "
     "configuration from the specified user slot.",
     "2 CC_RAIL_CONFIG_SAVE, CC_RAIL_CONFIG_LOAD"},
    {"SS-SLOT-002", L::kMust, N::kNothing,
     "LOAD of an empty slot or of a slot above 10 is refused and the active configuration stays",
     "If the slot is empty, an error will be returned and the load will not complete.",
     "2 CC_RAIL_CONFIG_LOAD"},
    {"SS-SLOT-003", L::kMust, N::kNothing,
     "The configuration saved to slot 0 is the active one after CC_RESET",
     "0 – Store the active configuration as the \"power on\" configuration. ... This command "
     "commits the data to NVM.",
     "2 CC_RAIL_CONFIG_SAVE"},
    {"SS-RESET-001", L::kMust, N::kNothing,
     "CC_RESET is acknowledged and the controller answers again afterwards",
     "Performs a software reset on the module.", "2 CC_RESET"},
    {"SS-RESET-002", L::kShould, N::kNothing,
     "After CC_RESET an unsaved setting is back at its power-on value",
     "0 – Load the active configuration with the \"power on\" configuration.",
     "2 CC_RAIL_CONFIG_LOAD; CC_RESET"},

    // --- Bezier curves (CC_MOTION_CONFIG / CC_MOTION_START, StackShot 3X; ERRATA 5) ---
    {"SS-CURVE-001", L::kMust, N::kThreeAxes,
     "A CC_MOTION_CONFIG meeting every listed requirement is accepted, a position jump between "
     "curves and a speed beyond the axis's maximum included (the list requires neither), and "
     "taken: CC_MOTION_START plays it to its last keyframe",
     "Motion paths in StackShot 3X are defined using cubic Bézier curves. Up to four curves can be "
     "specified to form a Bézier spline yielding five keyframes. ... A curve's initial P0.x must "
     "match the previous curves P3.x to provide continuity. ... Limits should be applied to "
     "prevent sudden velocity changes which may result in loss of steps.",
     "2 CC_MOTION_CONFIG; ERRATA 5"},
    {"SS-CURVE-002", L::kMust, N::kThreeAxes,
     "A curve 0 whose P0.x is not zero is refused BAD_PARAM",
     "Curve 0's starting time (P0.x) must be set to zero since it starts at time 0.",
     "2 CC_MOTION_CONFIG"},
    {"SS-CURVE-003", L::kMust, N::kThreeAxes,
     "A used curve whose P0.x differs from the previous curve's P3.x is refused BAD_PARAM",
     "A curve's initial P0.x must match the previous curves P3.x to provide continuity.",
     "2 CC_MOTION_CONFIG"},
    {"SS-CURVE-004", L::kMust, N::kThreeAxes,
     "P1.x below P0.x or P2.x above P3.x is refused BAD_PARAM",
     "Control point P1.x must not be less than P0.x. Likewise, control point P2.x must not be more "
     "than P3.x.",
     "2 CC_MOTION_CONFIG"},
    {"SS-CURVE-005", L::kMust, N::kThreeAxes,
     "CC_MOTION_START plays the configured spline: each position read while it plays lies on the "
     "curve (x the time in s, y the position in mm) and the axis rests on the last keyframe's "
     "position",
     "Motion paths in StackShot 3X are defined using cubic Bézier curves. ... All linear "
     "distances are specified in mm. ... The CC_MOTION_START command will begin the motion "
     "process.",
     "2 CC_MOTION_CONFIG, CC_MOTION_START"},

    // --- Reply deadlines (the runner's --deadline-ms; FACTS host timeouts) ---
    {"SS-DL-001", L::kShould, N::kNothing,
     "Reads (status, positions, ping, ids, settings) are answered within the deadline (kind "
     "\"query\")",
     "The host should set a read timeout sufficient to receive the response and to account for "
     "USB latency.",
     "2 Serial Communications Interface"},
    {"SS-DL-002", L::kShould, N::kNothing,
     "Writes (moves, stops, settings) are answered within the deadline (kind \"command\")",
     "Host tools read fixed reply lengths (6 bytes for write acks, 10 for status, 11 for position) "
     "with 1 s timeouts",
     "docs/device-facts.md, StackShot"},
    {"SS-DL-003", L::kShould, N::kNothing,
     "CC_SOFTWARE_CHECKSUM is answered within 1 s (the delay it is allowed stays within host "
     "timeouts)",
     "The checksum is performed upon command issue so a delay in the response is to be expected.",
     "2 CC_SOFTWARE_CHECKSUM; docs/device-facts.md, StackShot"},
};

}  // namespace

const std::vector<Rule>& StackshotRules() { return kStackshotRules; }

}  // namespace moco::conformance
