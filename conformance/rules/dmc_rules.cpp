// The DMC v2 rule catalogue (dmc-v2-protocol.txt; ERRATA dmc 1-11; FACTS "DMC v2").
// Clauses are quoted from the spec; where the spec is silent or garbled the
// ERRATA reading is quoted instead and the rule says so.
#include "conformance/rules/catalogue.h"
#include "conformance/rules/dmc_needs.h"

namespace moco::conformance {
namespace {

using L = Level;
using N = DmcNeeds;

const std::vector<Rule> kRules = {
    // --- Framing and checksum ("Message Format", "Computing and Validating the Checksum") ---
    {"DMC-FRAME-001", L::kMust, N::kNothing,
     "Every device byte belongs to a frame that starts with the 'D' 'F' marker",
     "Marker 2 BYTES Start of message. Byte sequence: { 'D' 'F' }", "Message Format"},
    {"DMC-FRAME-002", L::kMust, N::kNothing,
     "A device frame's Length is at most 1036 (the 1048-byte receive buffer less header and check "
     "bytes)",
     "The receiving buffer on the device must be at least 1048 bytes.",
     "Message Format; ERRATA 1.2"},
    {"DMC-FRAME-003", L::kMust, N::kNothing,
     "The device never leaves a frame unfinished (every frame it starts is completed)",
     "Every message has a Header. Additionally, some messages contain a variable-length Data "
     "section.",
     "Message Format"},
    {"DMC-FRAME-004", L::kShould, N::kNothing,
     "Device frame types have no bits outside 0x83FF (the reference parser drops such frames)",
     "the reference parser ... drops the frame and hunts again when ... the type has bits outside "
     "0x83FF",
     "docs/device-facts.md, DMC v2"},
    {"DMC-FRAME-005", L::kMust, N::kNothing,
     "Every device frame's data section fits the layout of its type",
     "Most messages have different data sections depending on if the message is coming from "
     "Dragonframe or from the device.",
     "Message Types"},
    {"DMC-CSUM-001", L::kMust, N::kNothing,
     "The Fletcher-16 checksum over every device frame, check bytes included, is zero",
     "outgoing messages add check bytes, so that the final computed checksum will be zero on the "
     "receiver end.",
     "Computing and Validating the Checksum; ERRATA 1.1"},
    {"DMC-CSUM-002", L::kMust, N::kNothing,
     "A request whose checksum is not zero is answered with ACK ERR_CHECKSUM",
     "For received messages, this checksum should be zero. If it is not the device should respond "
     "with response code ACK_ERR_CHECKSUM.",
     "Computing and Validating the Checksum"},
    {"DMC-CSUM-003", L::kShould, N::kNothing,
     "The ERR_CHECKSUM answer carries the ID and Type as received",
     "The response should use the message Type and ID from the received message.", "MSG_FLAG_ACK"},
    {"DMC-CSUM-004", L::kMust, N::kNothing,
     "A request with a valid checksum is never answered ERR_CHECKSUM",
     "ERR_CHECKSUM 0x0011 Checksum didn't match", "MSG_FLAG_ACK"},
    {"DMC-CSUM-005", L::kMust, N::kNothing,
     "After a corrupted frame the next valid request is answered normally",
     "The device must respond to every message it receives.", "MSG_FLAG_ACK"},

    // --- Answers ("MSG_FLAG_ACK"; ERRATA 1.4) ---
    {"DMC-ACK-001", L::kMust, N::kNothing, "Every request is answered (within the answer timeout)",
     "The device must respond to every message it receives.", "MSG_FLAG_ACK"},
    {"DMC-ACK-002", L::kMust, N::kNothing, "Every request is answered exactly once",
     "Some requests have specific responses that they expect. Some just expect a response with a "
     "MSG_FLAG_ACK set and a response code.",
     "MSG_FLAG_ACK; ERRATA 1.4"},
    {"DMC-ACK-003", L::kMust, N::kNothing,
     "An answer carries the ID of the request it answers (no answer with an ID that matches no "
     "request)",
     "The response should use the message Type and ID from the received message.", "MSG_FLAG_ACK"},
    {"DMC-ACK-004", L::kMust, N::kNothing,
     "An answer's Type is the request's Type (specific response) or the request's Type | 0x8000 "
     "(ACK)",
     "An ACK response is the request's Type | 0x8000 with the request's ID and a u16 response "
     "code.",
     "ERRATA 1.4"},
    {"DMC-ACK-005", L::kMust, N::kNothing,
     "An ACK's data section is the response code WORD (or the 32-bit form some firmware writes)",
     "Response Code WORD OK (0x0010) or appropriate Error Code", "MSG_FLAG_ACK"},
    {"DMC-ACK-006", L::kNote, N::kNothing, "ACK response codes written as 32-bit values",
     "A published DMC firmware built on dmc-lite writes the ACK response code as a 32-bit value "
     "(the spec says a 16-bit WORD; the low two bytes are the same)",
     "docs/device-facts.md, DMC v2"},
    {"DMC-ACK-007", L::kMust, N::kNothing,
     "An ACK's response code is one the spec lists (0x0010-0x0018, 0x0020-0x0023)",
     "OK 0x0010 ... ERR_HARD_LOW 0x0023", "MSG_FLAG_ACK"},
    {"DMC-ACK-008", L::kMust, N::kNothing,
     "A request with a specific response is answered with that response, not with ACK OK",
     "Requests with a specific response (HI, MOTOR_STATUS, MOTOR_MOVE, MOTOR_GET_POSITION, GIO_IN, "
     "VIRT_GET_POSITION, VIRT_AIM_POINT) answer with the plain Type and the request's ID.",
     "ERRATA 1.4"},
    {"DMC-ACK-009", L::kMust, N::kNothing,
     "A request whose response is \"None (MSG_FLAG_ACK + Response Code)\" is answered with an ACK",
     "Response Data None (MSG_FLAG_ACK + Response Code)", "Message Types"},
    {"DMC-ACK-010", L::kShould, N::kNothing,
     "An error code fits the request (limit codes for motion, pre/post-roll and not-in-position "
     "for real-time requests)",
     "ERR_PREROLL 0x0017 A real-time move preroll failed ... ERR_SOFT_UP 0x0020 Software upper "
     "limit hit",
     "MSG_FLAG_ACK"},
    {"DMC-ACK-011", L::kShould, N::kNothing,
     "Valid requests within the advertised capabilities are answered OK (or ERR_MOVING while "
     "motion is under way)",
     "OK 0x0010 Received, understood, and acted on message", "MSG_FLAG_ACK"},
    {"DMC-ACK-012", L::kNote, N::kNothing,
     "ACK code 0x0019 (the reference firmware's aim-point failure), which the spec does not list",
     "an extra error code 0x0019 for an aim-point failure", "docs/device-facts.md, DMC v2"},

    // --- Reply deadlines (runner options; the spec gives no number) ---
    {"DMC-DL-001", L::kShould, N::kNothing,
     "HI is answered within the deadline (--deadline-ms, default 250 ms)",
     "Dragonframe always starts with this request.", "MSG_HI"},
    {"DMC-DL-002", L::kShould, N::kNothing,
     "Queries (MOTOR_STATUS, MOTOR_GET_POSITION, GIO_IN, VIRT_GET_POSITION) are answered within "
     "the deadline",
     "The device must respond to every message it receives.", "MSG_FLAG_ACK"},
    {"DMC-DL-003", L::kShould, N::kNothing,
     "Motor and I/O commands are answered within the deadline",
     "The device must respond to every message it receives.", "MSG_FLAG_ACK"},
    {"DMC-DL-004", L::kShould, N::kNothing,
     "Upload messages (RT_UPLOAD_MOVE_*) are answered within the deadline",
     "The device must respond to every message it receives.", "MSG_FLAG_ACK"},
    {"DMC-DL-005", L::kShould, N::kNothing,
     "Real-time commands (POSITION_FRAME, RUN_MOVE, SHOOT_FRAME, GO, JOG_ALL) are answered within "
     "the deadline",
     "The device must respond to every message it receives.", "MSG_FLAG_ACK"},

    // --- MSG_HI ---
    {"DMC-HI-001", L::kMust, N::kNothing,
     "HI is answered with an HI response (Type 0x0001), not an ACK",
     "MSG_HI [0x0001] Request basic information about the device.", "MSG_HI; ERRATA 1.4"},
    {"DMC-HI-002", L::kMust, N::kNothing,
     "The HI response is 51 bytes (49 without PROTOCOL VERSION is a NOTE)",
     "MSG_HI response data is 51 bytes: name[32], fw major, minor, rev (u8 each), motor count "
     "(u8), DMX count (u16), GIO out (u8), GIO in (u8), HW limit sets (u8), upload frame count "
     "(u32), capabilities (u32), protocol version (u16).",
     "ERRATA 1.3"},
    {"DMC-HI-003", L::kNote, N::kNothing,
     "The HI response ends without PROTOCOL VERSION (49 bytes)",
     "Older devices end the HI reply without the PROTOCOL VERSION word (49 bytes instead of 51).",
     "docs/device-facts.md, DMC v2"},
    {"DMC-HI-004", L::kMust, N::kNothing, "MOTOR COUNT is 0-32",
     "MOTOR COUNT BYTE 0-32: Number of motors the device supports", "MSG_HI"},
    {"DMC-HI-005", L::kMust, N::kNothing, "DMX COUNT is 0-512",
     "DMX COUNT WORD 0-512: Number of DMX channels the device supports", "MSG_HI"},
    {"DMC-HI-006", L::kMust, N::kNothing, "GIO OUT COUNT is 0-32",
     "GIO OUT COUNT BYTE 0-32: Number of general IO output triggers (relay, logic out)", "MSG_HI"},
    {"DMC-HI-007", L::kMust, N::kNothing, "GIO INPUT COUNT is 0-32",
     "GIO INPUT COUNT BYTE 0-32: Number of input triggers", "MSG_HI"},
    {"DMC-HI-008", L::kMust, N::kNothing, "HW LIMIT COUNT is 0-32",
     "HW LIMIT COUNT BYTE 0-32: How many hardware limit set inputs the device has", "MSG_HI"},
    {"DMC-HI-009", L::kMust, N::kNothing, "PROTOCOL VERSION, when present, is 2",
     "PROTOCOL VERSION WORD 2", "MSG_HI"},
    {"DMC-HI-010", L::kShould, N::kNothing, "NAME is UTF-8 text filled with \\0 after its end",
     "Device name, up to 32 bytes, UTF-8 encoded. Fill with \\0 characters if less than 32 bytes",
     "MSG_HI"},
    {"DMC-HI-011", L::kShould, N::kNothing, "The device sends an unsolicited HI when it starts up",
     "Also, the device should issue a MSG_HI whenever it starts up.", "MSG_HI"},
    {"DMC-HI-012", L::kShould, N::kNothing, "Repeated HI requests get the same description",
     "Request basic information about the device.", "MSG_HI"},
    {"DMC-HI-013", L::kNote, N::kNothing,
     "CAPABILITIES has bits the spec does not define (above 0x0400)",
     "Each bit in the capabilities parameter represents functionality the device supports.",
     "MSG_HI Capabilities"},
    {"DMC-HI-014", L::kShould, N::kRealTime,
     "A real-time device can hold at least one uploaded frame (UPLOAD FRAME COUNT > 0)",
     "UPLOAD FRAME COUNT DWORD How many frames of position/dmx data can the device hold", "MSG_HI"},
    {"DMC-HI-015", L::kShould, N::kNothing,
     "Go-motion, looping and camera-trigger capabilities come with real-time moves (0x0001)",
     "MSG_RT_SHOOT_FRAME ... FRAME DWORD A frame in the uploaded move",
     "MSG_RT_SHOOT_FRAME; MSG_RT_RUN_MOVE FLAGS"},
    {"DMC-HI-016", L::kMust, N::kNothing,
     "The first HI a host sends is answered (not only a repeat after the host's timeout)",
     "Request basic information about the device. Dragonframe always starts with this "
     "request. ... The device must respond to every message it receives.",
     "MSG_HI; MSG_FLAG_ACK"},

    // --- Motor control ("Motor Control" capability, MSG_MOTOR_*) ---
    {"DMC-STAT-001", L::kMust, N::kNothing,
     "MOTOR_STATUS is answered with a 5-byte MOTOR_STATUS (DWORD bits, DMX byte)",
     "MOTOR STATUS DWORD Bit 1=motor moving, 0=not moving; DMX STATUS BYTE 1=DMX adjusting, 0=Not "
     "adjusting",
     "MSG_MOTOR_STATUS"},
    {"DMC-STAT-002", L::kMust, N::kNothing,
     "MOTOR_STATUS sets bits only for motors the device has (bit n-1 is motor n)",
     "MSG_MOTOR_STATUS: bit (n-1) of the u32 is motor n.", "ERRATA 1.5"},
    {"DMC-STAT-003", L::kMust, N::kNothing, "DMX STATUS is 0 or 1",
     "DMX STATUS BYTE 1=DMX adjusting, 0=Not adjusting", "MSG_MOTOR_STATUS"},
    {"DMC-STAT-004", L::kMust, N::kMotors,
     "MOTOR_STATUS shows a motor moving while it moves and at rest after it stopped",
     "This is only a status of whether something is moving/adjusting.", "MSG_MOTOR_STATUS"},
    {"DMC-MOVE-001", L::kMust, N::kMotors,
     "MOTOR_MOVE is answered with a 1-byte MOTOR_MOVE response (0 or 1) or an error ACK",
     "Response Data MOTOR STATUS BYTE 1=motor moving, 0=not moving", "MSG_MOTOR_MOVE"},
    {"DMC-MOVE-002", L::kShould, N::kMotors,
     "A move to a new position answers moving=1; a move to the current position answers 0",
     "MOTOR STATUS BYTE 1=motor moving, 0=not moving", "MSG_MOTOR_MOVE"},
    {"DMC-MOVE-003", L::kMust, N::kMotors,
     "A motor told to move comes to rest on the commanded position",
     "Instruct the device to move a motor to a new position.", "MSG_MOTOR_MOVE"},
    {"DMC-MOVE-004", L::kMust, N::kMotors, "A move never disturbs the other motors",
     "MOTOR BYTE Motor number, 1-MOTOR_COUNT", "MSG_MOTOR_MOVE"},
    {"DMC-POS-001", L::kMust, N::kNothing,
     "MOTOR_GET_POSITION carries MOVE TIME and one position per motor (4 + 4 x MOTOR COUNT bytes)",
     "MOVE TIME DWORD ... MOTOR-1 POS DWORD Motor 1 position ... MOTOR-N POS DWORD Final motor "
     "position",
     "MSG_MOTOR_GET_POSITION"},
    {"DMC-POS-002", L::kShould, N::kMotors,
     "While a motor moves, position updates arrive about every 100 ms (gaps at most "
     "--position-gap-ms, default 200)",
     "The device should send these out, about every 0.10 seconds, if any of the motors are moving",
     "MSG_MOTOR_GET_POSITION"},
    {"DMC-POS-003", L::kNote, N::kMotors,
     "Position updates come much more often than every 100 ms (dmc-lite sends every 40-60 ms)",
     "unsolicited MOTOR_GET_POSITION go out every 40-60 ms while moving, all with ID 0",
     "docs/device-facts.md, DMC v2"},
    {"DMC-POS-004", L::kShould, N::kMotors,
     "After motion stops, a position update reports the final position",
     "to keep Dragonframe informed of the positions.",
     "MSG_MOTOR_GET_POSITION; docs/protocol-notes"},
    {"DMC-POS-005", L::kShould, N::kMotors,
     "Positions reported during a move lie between the start and the target",
     "Instruct the device to move a motor to a new position.", "MSG_MOTOR_MOVE"},
    {"DMC-POS-006", L::kMust, N::kMotors,
     "MOTOR_GET_POSITION at rest reports where the motor was sent",
     "Request the motor positions and move 'time'.", "MSG_MOTOR_GET_POSITION"},
    {"DMC-RST-001", L::kMust, N::kMotors, "RESET_POSITION of a resting motor is acknowledged OK",
     "Instruct the device to reset a motor position to a new value. This does not move the motor.",
     "MSG_MOTOR_RESET_POSITION"},
    {"DMC-RST-002", L::kShould, N::kMotors,
     "RESET_POSITION is followed by a MOTOR_GET_POSITION message with the new position",
     "After changing the internal position and responding to this message, the device should send "
     "a MSG_MOTOR_GET_POSITION message to confirm the new position.",
     "MSG_MOTOR_RESET_POSITION"},
    {"DMC-RST-003", L::kMust, N::kMotors,
     "After RESET_POSITION the motor reports the new position and has not moved",
     "This does not move the motor.", "MSG_MOTOR_RESET_POSITION"},
    {"DMC-STOP-001", L::kMust, N::kMotors,
     "MOTOR_STOP is acknowledged OK and the motor comes to rest short of a far target",
     "Instruct the device to stop a motor.", "MSG_MOTOR_STOP"},
    {"DMC-STOP-002", L::kMust, N::kMotors,
     "MOTOR_STOP_ALL is acknowledged OK and every motor comes to rest",
     "Instruct the device to stop all motors. The device should decelerate.", "MSG_MOTOR_STOP_ALL"},
    {"DMC-STOP-003", L::kMust, N::kMotors,
     "MOTOR_STOP_ALL is accepted with and without its optional FLAGS",
     "Flags DWORD (Optional) 0x01 means silent", "MSG_MOTOR_STOP_ALL; ERRATA 1.7"},
    {"DMC-STOP-004", L::kShould, N::kMotors,
     "A second STOP_ALL soon after the first stops sooner than a single one (a hard stop)",
     "If the device gets a second STOP_ALL soon after a first, it should HARD STOP. Meaning it "
     "should decelerate faster than normal.",
     "MSG_MOTOR_STOP_ALL"},
    {"DMC-STOP-005", L::kShould, N::kMotors,
     "MOTOR_STOP_ALL decelerates: a motor at speed travels on after the STOP_ALL is answered "
     "instead of halting",
     "The device should decelerate. (If a controller may move large/heavy equipment, it should "
     "always decelerate rather than simply stop sending signals.)",
     "MSG_MOTOR_STOP_ALL"},
    {"DMC-CFG-001", L::kMust, N::kMotors,
     "MOTOR_SET_SPEED with positive velocity and acceleration is acknowledged OK",
     "MAX VELOCITY DWORD The maximum steps per second the motor can go; MAX ACCEL DWORD The "
     "maximum acceleration",
     "MSG_MOTOR_SET_SPEED"},
    {"DMC-CFG-002", L::kMust, N::kMotors,
     "MOTOR_CONFIGURE is acknowledged OK, unknown flag bits included",
     "dmc-lite's header also defines MOTOR_CONFIGURE flags beyond the spec's two ... Accept "
     "unknown flag bits without error.",
     "MSG_MOTOR_CONFIGURE; docs/device-facts.md, DMC v2"},
    {"DMC-CFG-003", L::kMust, N::kMotors,
     "MOTOR_JOG is acknowledged OK and the motor moves towards the destination",
     "Instruct the device to jog/inch a motor.", "MSG_MOTOR_JOG"},
    {"DMC-CFG-004", L::kShould, N::kMotors,
     "MOTOR_JOG with SPEED outside 1-10000 is refused with ERR_RANGE",
     "SPEED WORD 1=inching, 10000=jog at max velocity", "MSG_MOTOR_JOG"},
    {"DMC-CFG-005", L::kMust, N::kMotors, "MOTOR_SET_LIMITS is acknowledged OK",
     "Set the motor software and hardware limits.", "MSG_MOTOR_SET_LIMITS"},
    {"DMC-CFG-006", L::kShould, N::kMotors,
     "MOTOR_JOG SPEED sets the pace: a lower SPEED covers less ground in the same time, and "
     "SPEED 1 at most a tenth of what SPEED 10000 covers",
     "A speed of 1 means the device should move very slowly, for precise adjustments. A speed of "
     "10,000 means the device should jog using the max velocity and acceleration. A value in "
     "between 1 and 10,000 should provide an appropriate speed between 1% and 100% of the jog "
     "speed.",
     "MSG_MOTOR_JOG"},
    {"DMC-CFG-007", L::kShould, N::kCoupleMotors,
     "With capability 0x0100, MOTOR_CONFIGURE coupling a motor (flag 0x10, or 0x20 reversed) and "
     "uncoupling it are acknowledged OK",
     "0x0100 Couple motors; dmc-lite's header also defines MOTOR_CONFIGURE flags beyond the "
     "spec's two: ... 0x10 coupled, 0x20 coupled reversed (capability 0x0100 \"couple motors\")",
     "Capabilities; docs/device-facts.md, DMC v2"},
    {"DMC-CFG-008", L::kNote, N::kCoupleMotors,
     "A motor coupled with flag 0x10 makes the steps of the motor before it (mirrored with 0x20), "
     "and moves on its own again once uncoupled",
     "0x10 coupled, 0x20 coupled reversed (capability 0x0100 \"couple motors\")",
     "Capabilities; docs/device-facts.md, DMC v2"},

    // --- Errors ---
    {"DMC-ERR-001", L::kMust, N::kMotors, "Motor number 0 is refused with ERR_RANGE",
     "Any reference to a motor number is 1-based.", "Introduction; ERRATA 1.11"},
    {"DMC-ERR-002", L::kMust, N::kMotors,
     "A motor number above MOTOR COUNT is refused with ERR_RANGE",
     "MOTOR BYTE Motor number, 1-MOTOR_COUNT", "MSG_MOTOR_*; ERRATA 1.11"},
    {"DMC-ERR-003", L::kMust, N::kNothing, "An unknown message type is answered ERR_UNSUPPORTED",
     "ERR_UNSUPPORTED 0x0013 The message type is not known or supported", "MSG_FLAG_ACK"},
    {"DMC-ERR-004", L::kShould, N::kNothing,
     "The pre-2018 VIRT_JOG_ON_LINE type 0x0204 is answered ERR_UNSUPPORTED",
     "Changed MSG_VIRT_JOG_ON_LINE from 0x0204 to 0x0206", "Document Revision History"},
    {"DMC-ERR-005", L::kMust, N::kNothing,
     "A known type with data shorter than its layout is answered with an error, never OK",
     "OK 0x0010 Received, understood, and acted on message", "MSG_FLAG_ACK"},
    {"DMC-ERR-006", L::kNote, N::kNothing,
     "A malformed request (wrong length) is answered with a code other than ERR_GENERAL",
     "a layout whose length does not fit ... is ERR_GENERAL (a malformed message, no single "
     "parameter out of range)",
     "docs/protocol-notes (dmc SuggestedAck)"},
    {"DMC-ERR-007", L::kMust, N::kNothing,
     "Noise between frames does not stop the device answering the next frame",
     "Marker 2 BYTES Start of message. Byte sequence: { 'D' 'F' }", "Message Format"},
    {"DMC-ERR-008", L::kShould, N::kNothing,
     "A header declaring a Length no device buffer holds (65535) does not stop the device "
     "answering the next frame",
     "A Length above that is a framing error, not an allocation. (The 1048 bytes are a minimum: "
     "a device with a larger buffer rightly waits for a Length it can hold; the reference parser "
     "drops a frame whose length exceeds its buffer.)",
     "ERRATA 1.2; docs/device-facts.md, DMC v2"},
    {"DMC-ERR-009", L::kMust, N::kNothing,
     "A request delivered one byte at a time is answered as a whole one",
     "The receiving buffer on the device must be at least 1048 bytes.", "Message Format"},
    {"DMC-ERR-010", L::kShould, N::kNoVirtual,
     "Messages of a capability the device does not advertise are answered ERR_UNSUPPORTED",
     "If the device advertises virtuals, Dragonframe expects it to handle the following commands",
     "Capabilities"},
    {"DMC-ERR-011", L::kShould, N::kDmx, "MSG_DMX with START CHANNEL 0 is refused with ERR_RANGE",
     "START CHANNEL WORD First channel of lighting values, 1-512", "MSG_DMX"},
    {"DMC-ERR-012", L::kMust, N::kNothing,
     "The largest frame the receive buffer must hold (1048 bytes, an unknown Type) is read whole "
     "and answered ERR_UNSUPPORTED",
     "The receiving buffer on the device must be at least 1048 bytes.", "Message Format"},
    {"DMC-ERR-013", L::kNote, N::kNothing,
     "Bytes after a known layout are refused (a device may ignore them and carry the message out)",
     "Added PROTOCOL VERSION to end of HI message.",
     "Document Revision History; docs/protocol-notes (trailing bytes)"},

    // --- Soft limits ---
    {"DMC-LIM-001", L::kNote, N::kMotors,
     "A move above an enabled upper soft limit is refused with ERR_SOFT_UP (no clause says a "
     "device refuses it; dmc-lite completes it)",
     "ERR_SOFT_UP 0x0020 Software upper limit hit", "MSG_FLAG_ACK; MSG_MOTOR_SET_LIMITS"},
    {"DMC-LIM-002", L::kNote, N::kMotors,
     "A move below an enabled lower soft limit is refused with ERR_SOFT_LOW (no clause says a "
     "device refuses it; dmc-lite completes it)",
     "ERR_SOFT_LOW 0x0021 Software lower limit hit", "MSG_FLAG_ACK; MSG_MOTOR_SET_LIMITS"},
    {"DMC-LIM-003", L::kMust, N::kMotors,
     "A move the device refuses (ERR_SOFT_UP / ERR_SOFT_LOW) leaves the motor where it was",
     "ERR_SOFT_UP 0x0020 Software upper limit hit", "MSG_FLAG_ACK"},
    {"DMC-LIM-004", L::kMust, N::kMotors, "A move within enabled soft limits is carried out",
     "LOWER LIMIT DWORD The lower software step limit; UPPER LIMIT DWORD The upper software step "
     "limit",
     "MSG_MOTOR_SET_LIMITS"},
    {"DMC-LIM-005", L::kMust, N::kMotors, "Disabled soft limits do not restrict moves",
     "LOWER ENABLE BYTE 0x01 enabled, 0x00 not", "MSG_MOTOR_SET_LIMITS"},
    {"DMC-LIM-006", L::kNote, N::kMotors,
     "A jog towards a point past an enabled soft limit stops at the limit (no clause says how a "
     "jog meets one; dmc-lite completes it)",
     "UPPER LIMIT DWORD The upper software step limit", "MSG_MOTOR_SET_LIMITS; MSG_MOTOR_JOG"},
    {"DMC-LIM-007", L::kShould, N::kHwLimits,
     "A hardware limit switch that closes while its bound motor moves towards it halts the motor "
     "and is reported by MOTOR_HARD_STOP with REASON 1 (upper) or 2 (lower) and that MOTOR",
     "The device can send this when a limit has been hit ... REASON BYTE 1=Upper Limit, 2=Lower "
     "Limit; MOTOR BYTE Motor number (only present if REASON is 1 or 2)",
     "MSG_MOTOR_HARD_STOP; MSG_MOTOR_SET_LIMITS (HW SET)"},

    // --- Unsolicited messages (ERRATA 1.9) ---
    {"DMC-UNS-001", L::kMust, N::kNothing,
     "Frames the device sends unprompted are only HI, MOTOR_GET_POSITION, GIO_IN, MOTOR_HARD_STOP, "
     "RT_END or VIRT_AIM_POINT",
     "Messages the device sends unprompted (HI at start-up/reset, MOTOR_GET_POSITION updates, "
     "GIO_IN on change, MOTOR_HARD_STOP, RT_END, VIRT_AIM_POINT) carry a device-side sequence ID.",
     "ERRATA 1.9"},
    {"DMC-UNS-002", L::kMust, N::kMotors,
     "The device does not stall when the host does not ACK its unsolicited messages",
     "The host answers them with an ACK; a device must not stall waiting for that ACK.",
     "ERRATA 1.9"},
    {"DMC-UNS-003", L::kMust, N::kNothing,
     "MOTOR_HARD_STOP carries REASON 0, 1, 2 or 100, and MOTOR only (and always) with 1 or 2",
     "REASON BYTE 0=E-Stop/General, 1=Upper Limit, 2=Lower Limit, 100=Engine Exception; MOTOR BYTE "
     "... (only present if REASON is 1 or 2)",
     "MSG_MOTOR_HARD_STOP"},
    {"DMC-UNS-004", L::kNote, N::kMotors,
     "The device answers the host's ACK of its unsolicited messages (the reference firmware "
     "answers ERR_UNSUPPORTED; ignoring it is as good)",
     "The device must respond to every message it receives. / The host answers them with an ACK",
     "MSG_FLAG_ACK; ERRATA 1.9; docs/device-facts.md, DMC v2"},

    // --- I/O and DMX ---
    {"DMC-GIO-001", L::kMust, N::kNothing, "GIO_IN is answered with a 4-byte GIO_IN response",
     "MSG_GIO_IN: the request carries no data; the response (and the unsolicited message on input "
     "change) carries the u32 trigger bits.",
     "ERRATA 1.6"},
    {"DMC-GIO-002", L::kShould, N::kGioIn, "GIO_IN sets bits only for inputs the device has",
     "GIO INPUT COUNT BYTE 0-32: Number of input triggers", "MSG_HI; MSG_GIO_IN"},
    {"DMC-GIO-003", L::kMust, N::kGioOut,
     "GIO_OUT within the advertised outputs is acknowledged OK",
     "Set the state for general I/O output triggers.", "MSG_GIO_OUT"},
    {"DMC-GIO-004", L::kMust, N::kNothing, "GIO_CAM is acknowledged OK", "Test the camera outputs.",
     "MSG_GIO_CAM"},
    {"DMC-GIO-005", L::kShould, N::kGioIn,
     "A change of a general I/O input is sent unsolicited as GIO_IN carrying the new TRIGGERS",
     "The device should also send this message, unsolicited, any time the inputs change.",
     "MSG_GIO_IN"},
    {"DMC-DMX-001", L::kMust, N::kDmx, "MSG_DMX within the advertised channels is acknowledged OK",
     "Set DMX light values. The request specifies the initial channel to change, and then one or "
     "more light values.",
     "MSG_DMX"},
    {"DMC-DMX-002", L::kShould, N::kDmx,
     "After MSG_DMX with RAMP 1 changing a level, MOTOR_STATUS reports DMX STATUS 1 (adjusting)",
     "If RAMP is set to 1, the device should ramp the light value of each channel up or down to "
     "reach the target channel, rather than switching to it immediately. ... DMX STATUS BYTE "
     "1=DMX adjusting, 0=Not adjusting",
     "MSG_DMX; MSG_MOTOR_STATUS"},
    {"DMC-DMX-003", L::kMust, N::kDmx,
     "A DMX ramp ends: MOTOR_STATUS reports DMX STATUS 0 again within 30 s of a full-range ramp",
     "Request the motor (and dmx) status. This is only a status of whether something is "
     "moving/adjusting.",
     "MSG_MOTOR_STATUS"},
    {"DMC-DMX-004", L::kShould, N::kDmx,
     "MSG_DMX with RAMP 0 switches at once: MOTOR_STATUS right after it reports DMX STATUS 0",
     "RAMP BYTE 1=ramp, 0=immediate", "MSG_DMX"},
    {"DMC-DMX-005", L::kMust, N::kRtDmx,
     "RT_UPLOAD_MOVE_DMX sections of channels within DMX COUNT and frames within the upload are "
     "acknowledged OK",
     "If the device advertises real-time capabilities, Dragonframe expects it to handle the "
     "following commands: ... MSG_RT_UPLOAD_MOVE_DMX (only if the device also support DMX)",
     "Real-time Moves; MSG_RT_UPLOAD_MOVE_DMX"},
    {"DMC-DMX-006", L::kShould, N::kRtDmx,
     "RT_UPLOAD_MOVE_DMX for channel 0, a channel past DMX COUNT or frames past END FRAME is "
     "refused with ERR_RANGE",
     "CHANNEL WORD The DMX channel ... ERR_RANGE 0x0014 A parameter was out of range",
     "MSG_RT_UPLOAD_MOVE_DMX; MSG_FLAG_ACK"},
    {"DMC-DMX-007", L::kMust, N::kRtDmx,
     "RT_POSITION_FRAME sets the uploaded DMX channels to their levels at that frame (observed "
     "in-process)",
     "Instructs the device to send all motors (and DMX if applicable) to the uploaded frame "
     "position.",
     "MSG_RT_POSITION_FRAME"},
    {"DMC-DMX-008", L::kMust, N::kRtDmx,
     "After a channel's last set of DMX data its final level repeats until END FRAME (observed "
     "in-process)",
     "If the high bit is set (0x80000000), then this is the last set of DMX data for this channel. "
     "That means the device must repeat the final value until the end of the uploaded move frame "
     "range",
     "MSG_RT_UPLOAD_MOVE_DMX"},
    {"DMC-DMX-009", L::kMust, N::kRtDmx,
     "During a live run with SYNC DMX 1 the uploaded channels hold each frame's uploaded level "
     "when the frame is reported (observed in-process)",
     "SYNC DMX BYTE 1=Play back upload DMX, 0=don't play DMX", "MSG_RT_RUN_MOVE"},
    {"DMC-DMX-010", L::kShould, N::kRtDmx,
     "A live run with SYNC DMX 0 leaves the DMX channels at the levels MSG_DMX set (observed "
     "in-process)",
     "SYNC DMX BYTE 1=Play back upload DMX, 0=don't play DMX", "MSG_RT_RUN_MOVE"},
    {"DMC-DMX-011", L::kNote, N::kRtDmx,
     "BLOOP DMX CHANNEL goes to full level (255) once during the run for about BLOOP TIME, then "
     "back (observed in-process)",
     "BLOOP DMX CHANNEL WORD 0=None, 1-512 = a channel for the BLOOP; BLOOP TIME WORD Bloop time "
     "(approx) in ms",
     "MSG_RT_RUN_MOVE"},

    // --- Real-time moves ---
    {"DMC-RT-001", L::kMust, N::kRealTime,
     "RT_UPLOAD_MOVE_BEGIN, _AXIS and _END of a valid move are acknowledged OK",
     "MSG_RT_UPLOAD_MOVE_BEGIN ... MSG_RT_UPLOAD_MOVE_AXIS ... MSG_RT_UPLOAD_MOVE_END",
     "Real-time Moves"},
    {"DMC-RT-002", L::kMust, N::kRealTime,
     "RT_POSITION_FRAME sends every uploaded motor to its position at that frame",
     "Instructs the device to send all motors (and DMX if applicable) to the uploaded frame "
     "position.",
     "MSG_RT_POSITION_FRAME"},
    {"DMC-RT-003", L::kMust, N::kRealTime,
     "After the last set, the final value repeats until END FRAME",
     "That means the device must repeat the final value until the end of the uploaded move frame "
     "range",
     "MSG_RT_UPLOAD_MOVE_AXIS"},
    {"DMC-RT-004", L::kMust, N::kRealTime,
     "During a live move a MOTOR_GET_POSITION arrives at each new frame with MOVE TIME = frame x "
     "1000",
     "If the device is running a live move (configured via MSG_RT_RUN_MOVE), it must send a "
     "MSG_MOTOR_GET_POSITION each time it reaches a new frame in the move.",
     "MSG_RT_GO; MSG_MOTOR_GET_POSITION"},
    {"DMC-RT-005", L::kMust, N::kRealTime, "RT_END follows the end of a live run",
     "After a MSG_RT_RUN_MOVE or MSG_RT_SHOOT_FRAME has finished shooting, the device sends "
     "MSG_RT_END to notify Dragonframe that the process is over.",
     "MSG_RT_END"},
    {"DMC-RT-006", L::kMust, N::kRealTime,
     "RT_END has an empty data section and is sent once per run",
     "MSG_RT_END [0x0114] ... Request Data None", "MSG_RT_END"},
    {"DMC-RT-007", L::kShould, N::kRealTime,
     "Frame reports of a live move come at about the frame interval (1 / FPS)",
     "it must send a MSG_MOTOR_GET_POSITION each time it reaches a new frame in the move. (If it "
     "is slightly after, that is ok.)",
     "MSG_RT_GO"},
    {"DMC-RT-008", L::kShould, N::kRealTime,
     "At a frame report each motor is within the uploaded path between that frame and the next",
     "Current position in move (if playing back), in thousandths of a frame.",
     "MSG_MOTOR_GET_POSITION"},
    {"DMC-RT-009", L::kMust, N::kRealTime,
     "RT_RUN_MOVE is accepted without its optional trailing fields (29 bytes) and GO after the "
     "pre-roll is OK",
     "Optional trailing fields: ... the MSG_RT_RUN_MOVE fields after BLOOP TIME (FLAGS, camera "
     "angles) ... A device must accept each shorter form.",
     "ERRATA 1.7"},
    {"DMC-RT-010", L::kNote, N::kRealTime,
     "RT_POSITION_FRAME outside the uploaded range is refused",
     "FRAME DWORD The frame to send all motors to", "MSG_RT_POSITION_FRAME"},
    {"DMC-RT-011", L::kShould, N::kRealTime, "RT_GO with nothing armed is refused",
     "After a MSG_RT_RUN_MOVE or MSG_RT_SHOOT_FRAME the device may move the motors into position. "
     "When the device has stopped moving, a MSG_RT_GO command will perform the run or shoot of the "
     "frame.",
     "MSG_RT_GO"},
    {"DMC-RT-012", L::kNote, N::kRealTime, "STOP_ALL during a live run ends it with RT_END",
     "the device sends MSG_RT_END to notify Dragonframe that the process is over.", "MSG_RT_END"},
    {"DMC-RT-013", L::kMust, N::kRealTime,
     "RT_JOG_ALL from a frame position is acknowledged OK and reports each frame reached",
     "Jog all motors towards the destination frame. The rig must already be on a frame position "
     "that is uploaded to the device.",
     "MSG_RT_JOG_ALL"},
    {"DMC-RT-014", L::kShould, N::kRealTime,
     "RT_JOG_ALL when the rig is not on an uploaded frame position is refused "
     "(ERR_NOT_IN_POSITION)",
     "ERR_NOT_IN_POSITION 0x0016 ... if you attempt to jog all but aren't on a frame position.",
     "MSG_FLAG_ACK"},
    {"DMC-RT-015", L::kShould, N::kRealTime,
     "RT_GO is accepted as soon as the armed rig rests (no ERR_NOT_IN_POSITION while it arms)",
     "When the device has stopped moving, a MSG_RT_GO command will perform the run or shoot of the "
     "frame.",
     "MSG_RT_GO"},
    {"DMC-RT-016", L::kNote, N::kRealTime,
     "A motor sent to an uploaded frame reads exactly the uploaded position",
     "an uploaded frame reads back exactly (200)", "docs/device-facts.md, DMC v2"},
    {"DMC-RT-017", L::kShould, N::kRtTriggers,
     "RT_UPLOAD_MOVE_TRIGGERS with frame indices within the upload is acknowledged OK",
     "MSG_RT_UPLOAD_MOVE_TRIGGERS [0x0104] Introduced in Protocol: 2 Send a section of trigger "
     "data. Only sent if the DMX program has triggers.",
     "MSG_RT_UPLOAD_MOVE_TRIGGERS"},
    {"DMC-RT-018", L::kShould, N::kRtTriggers,
     "RT_UPLOAD_MOVE_TRIGGERS with a frame index past the upload is refused with ERR_RANGE",
     "FRAME DWORD Frame index (frame - start) ... ERR_RANGE 0x0014 A parameter was out of range",
     "MSG_RT_UPLOAD_MOVE_TRIGGERS; MSG_FLAG_ACK"},
    {"DMC-RT-019", L::kShould, N::kRtTriggers,
     "During a live run with SYNC DMX 1 the GIO outputs under MASK hold each frame's uploaded "
     "trigger values (0 where none was sent) (observed in-process)",
     "MASK DWORD The trigger mask ... Only sends frame/value pairs where one or more triggers is "
     "on. ... VALUES DWORD Trigger values",
     "MSG_RT_UPLOAD_MOVE_TRIGGERS"},
    {"DMC-RT-020", L::kShould, N::kRtTriggers,
     "The GIO outputs of BLOOP LOCATION turn on once during the run for about BLOOP TIME "
     "(observed in-process)",
     "BLOOP LOCATION DWORD GIO Outputs for \"bloop\" signal ... BLOOP TIME WORD Bloop time "
     "(approx) in ms",
     "MSG_RT_RUN_MOVE"},
    {"DMC-RT-021", L::kMust, N::kRtCamera,
     "RT_RUN_MOVE with camera FLAGS (0x10 video, 0x20 stills with angles) is acknowledged OK, "
     "GO is OK and RT_END follows the run",
     "FLAGS WORD Only set if capability 0x0200 (real-time looping) or 0x0400 (real-time camera) "
     "are set. ... 0x10 is camera trigger at start/stop of move (video) 0x20 is camera trigger for "
     "every frame (stills)",
     "MSG_RT_RUN_MOVE; Capabilities"},
    {"DMC-RT-022", L::kMust, N::kRtCamera,
     "With FLAGS 0x20 (stills) the camera shutter fires once for every frame of the run, start "
     "and end frames included (observed in-process)",
     "0x20 is camera trigger for every frame (stills)", "MSG_RT_RUN_MOVE"},
    {"DMC-RT-023", L::kShould, N::kRtCamera,
     "A stills exposure is open from CAMERA OPEN ANGLE to CAMERA CLOSE ANGLE of its frame's "
     "interval (observed in-process, within a tenth of a frame)",
     "CAMERA OPEN ANGLE WORD Only used if camera trigger for every frame, 0-360 degrees; CAMERA "
     "CLOSE ANGLE WORD Only used if camera trigger for every frame, 0-360 degrees",
     "MSG_RT_RUN_MOVE"},
    {"DMC-RT-024", L::kShould, N::kRtCamera,
     "RT_RUN_MOVE with stills and a camera angle past 360 is refused with ERR_RANGE",
     "CAMERA OPEN ANGLE WORD ... 0-360 degrees ... ERR_RANGE 0x0014 A parameter was out of range",
     "MSG_RT_RUN_MOVE; MSG_FLAG_ACK"},
    {"DMC-RT-025", L::kShould, N::kRtCamera,
     "With FLAGS 0x10 (video) the shutter line is pressed once as the run reaches its start "
     "frame and once at its end frame (observed in-process)",
     "0x10 is camera trigger at start/stop of move (video)", "MSG_RT_RUN_MOVE"},
    {"DMC-RT-026", L::kShould, N::kRealTime,
     "RT_RUN_MOVE whose pre-roll would take a motor past an enabled soft limit is refused with "
     "ERR_PREROLL",
     "ERR_PREROLL 0x0017 A real-time move preroll failed, usually because preroll would send "
     "motors past limits.",
     "MSG_FLAG_ACK; MSG_RT_RUN_MOVE"},
    {"DMC-RT-027", L::kShould, N::kRealTime,
     "RT_RUN_MOVE whose post-roll would take a motor past an enabled soft limit is refused with "
     "ERR_POSTROLL",
     "ERR_POSTROLL 0x0018 A real-time move postroll failed, usually because a limit check failed.",
     "MSG_FLAG_ACK; MSG_RT_RUN_MOVE"},
    {"DMC-RT-028", L::kMust, N::kRealTime,
     "An RT_RUN_MOVE refused for its pre- or post-roll leaves every motor where it was",
     "The rig must move into a pre-roll position that it calculates ... ERR_PREROLL ... preroll "
     "would send motors past limits",
     "MSG_RT_RUN_MOVE; MSG_FLAG_ACK"},
    {"DMC-RT-029", L::kMust, N::kRealTime,
     "RT_RUN_MOVE whose pre-roll and post-roll stay within enabled soft limits is acknowledged OK "
     "and runs",
     "Prepares the device to run a section of the move live. The rig must move into a pre-roll "
     "position that it calculates",
     "MSG_RT_RUN_MOVE"},
    {"DMC-GM-001", L::kMust, N::kGoMotion,
     "RT_SHOOT_FRAME then RT_GO are acknowledged OK and RT_END follows the exposure",
     "Set up a blur-motion frame capture", "MSG_RT_SHOOT_FRAME; MSG_RT_END"},
    {"DMC-GM-002", L::kMust, N::kGoMotion2,
     "RT_SHOOT_FRAME2 then RT_GO are acknowledged OK and RT_END follows the exposure",
     "Set up a blur-motion frame capture (alternate version)", "MSG_RT_SHOOT_FRAME2; ERRATA 1.8"},
    {"DMC-LOOP-001", L::kMust, N::kLooping, "RT_STOP_LOOP is acknowledged OK",
     "If the device supports 'real-time looping' capability, it must support this command.",
     "MSG_RT_STOP_LOOP"},

    // --- Virtuals ---
    {"DMC-VIRT-001", L::kMust, N::kVirtual,
     "VIRT_GET_POSITION is answered with 24 bytes (37 with the aim point)",
     "vTrack POS ... vRoll POS DWORD ... Aim pt enabled BYTE This and below are only if device "
     "supports aim point",
     "MSG_VIRT_GET_POSITION"},
    {"DMC-VIRT-002", L::kMust, N::kVirtualBoomRig,
     "VIRT_CONFIG boom-swing-track (TYPE 1) is acknowledged OK in each length form (93, 97, 577, "
     "581 data bytes)",
     "TYPE = 1 (Boom-Swing-Track) ... Boom Compensation Table DWORD * 121 Optional ... SAFE "
     "DISTANCE DWORD Safe distance * 1000 (optional)",
     "MSG_VIRT_CONFIG; ERRATA 1.7"},
    {"DMC-VIRT-003", L::kMust, N::kVirtualBoomRig,
     "VIRT_MOVE to a reachable target is acknowledged OK and VIRT_GET_POSITION then reports the "
     "target on that axis (within 0.002)",
     "Send the virtual motor to a new position. POSITION DWORD Target position * 100000",
     "MSG_VIRT_MOVE; MSG_VIRT_GET_POSITION"},
    {"DMC-VIRT-004", L::kMust, N::kVirtualBoomRig,
     "VIRT_MOVE to a target the rig cannot reach is refused and moves nothing",
     "Inverse: P = target - R o; b = asin(P.z / L) ... |P.z| > L or |P.x| > h is unreachable "
     "(ERR_RANGE).",
     "docs/device-facts.md, Boom rig virtual axes"},
    {"DMC-VIRT-005", L::kShould, N::kVirtualBoomRig,
     "An unreachable VIRT_MOVE target is refused with ERR_RANGE",
     "ERR_RANGE 0x0014 A parameter was out of range; |P.z| > L or |P.x| > h is unreachable "
     "(ERR_RANGE).",
     "MSG_FLAG_ACK; docs/device-facts.md, Boom rig virtual axes"},
    {"DMC-VIRT-006", L::kShould, N::kVirtual,
     "VIRT_MOVE and VIRT_STOP with virtual motor 0 or 7 are refused with ERR_RANGE",
     "Virtual axis numbers: TRACK=1, EW=2, NS=3, PAN=4, TILT=5, ROLL=6.",
     "docs/device-facts.md, Boom rig virtual axes; ERRATA 1.11"},
    {"DMC-VIRT-007", L::kMust, N::kVirtualBoomRig,
     "VIRT_STOP during a virtual move is acknowledged OK and the rig comes to rest short of the "
     "target",
     "Stop the virtual motor.", "MSG_VIRT_STOP"},
    {"DMC-VIRT-008", L::kMust, N::kVirtualBoomRig,
     "VIRT_JOG is acknowledged OK and reaches its destination; VIRT_JOG_ON_LINE is acknowledged OK "
     "and speed 0 or VIRT_STOP brings the rig to rest",
     "Instruct the device to jog/inch a virtual motor. ... Instruct the device to jog along the "
     "direction of the camera.",
     "MSG_VIRT_JOG; MSG_VIRT_JOG_ON_LINE; ERRATA 1.10"},
    {"DMC-VIRT-009", L::kMust, N::kAimPoint,
     "VIRT_AIM_POINT is answered with the same data (13 bytes: ENABLE, AIM-X, AIM-Y, AIM-Z)",
     "The response contains the same data.", "MSG_VIRT_AIM_POINT"},
    {"DMC-VIRT-010", L::kShould, N::kAimPoint,
     "VIRT_GET_POSITION's aim fields report the aim point in force",
     "Aim pt enabled BYTE This and below are only if device supports aim point; aim-x DWORD X * "
     "1000",
     "MSG_VIRT_GET_POSITION"},
    {"DMC-VIRT-011", L::kShould, N::kVirtual,
     "The four virtual mode capabilities (0x0004, 0x0008, 0x0010, 0x0020) are advertised together",
     "Dragonframe reportedly refused a device that advertised only the boom-swing-track "
     "capability bit; that firmware advertises all four virtual bits.",
     "docs/device-facts.md, Boom rig virtual axes"},
    {"DMC-VIRT-012", L::kNote, N::kVirtual,
     "VIRT_CONFIG TYPE numbers the rigs 0..4 as the spec does; a device accepting TYPE 8 as x-y-z "
     "takes a dmc-lite-derived firmware's bit-flag numbering",
     "TYPE BYTE 0=none 1=boom-swing-track 2=swing-pan, 3=y-swing-track 4=x-y-z; a "
     "dmc-lite-derived header instead uses bit flags (0x01 BST, 0x02 swing-pan, 0x04 "
     "y-swing-track, 0x08 x-y-z)",
     "MSG_VIRT_CONFIG; docs/device-facts.md, Boom rig virtual axes"},
};

}  // namespace

const std::vector<Rule>& DmcRules() { return kRules; }

}  // namespace moco::conformance
