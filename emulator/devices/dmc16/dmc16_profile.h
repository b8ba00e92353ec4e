// The DMC-16's description (fixtures/profiles/dmc16.json): what MSG_HI
// advertises (dmc-v2-protocol.txt "MSG_HI", "Capabilities"; ERRATA dmc 3),
// the line, the motion defaults and the rig's limit-switch placement.
#ifndef MOCO_DEVICES_DMC16_DMC16_PROFILE_H_
#define MOCO_DEVICES_DMC16_DMC16_PROFILE_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "devices/usb_bridge.h"
#include "physics/bullet/rig_dynamics.h"
#include "wire/dmc.h"
#include "wire/dmc_constants.h"

namespace moco::devices {

struct Dmc16LimitSet {
  int set = 1;  // 1..hw_limit_sets
  std::optional<int64_t> low_steps;
  std::optional<int64_t> high_steps;
};

// The virtual axes (MSG_VIRT_*; FACTS "Boom rig virtual axes").
struct Dmc16Virtual {
  bool enabled = false;
  // Advertised in HI when enabled: FACTS: Dragonframe refused a device with
  // the boom-swing-track bit alone, so all four modes, plus the aim point.
  uint32_t capabilities = 0x007c;  // within 0x007c
  // VIRT_JOG_ON_LINE at SPEED 10000: along X/Y/Z in user units per second,
  // PAN/TILT in degrees per second (SPEED scales linearly).
  double jog_line_units_per_s = 1.0;
  double jog_angle_deg_per_s = 30.0;
};

// The physical boom rig the motors drive (physics/bullet, docs/rig-dynamics.md):
// when enabled the device steps a Bullet model of the rig from its motors'
// step counts and treats a collision of the camera head as an e-stop.
struct Dmc16PhysicalRig {
  bool enabled = false;
  std::string rig_path;  // the rig profile file, as written (relative to the device profile)
  physics::RigProfile rig;
  // The DMC motor (1..motor_count) driving each joint in physics::Joint order
  // (track, swing, boom, pan, tilt, roll); 0 holds the joint at its home.
  std::array<int, physics::kJointCount> motors{1, 2, 3, 4, 5, 6};
};

// The largest receive buffer a profile may declare (behaviour.receive_buffer_bytes).
inline constexpr uint32_t kMaxReceiveBuffer = static_cast<uint32_t>(dmc::kLargestReceiveBuffer);

// Where a device departs from the spec's reading (docs/devices/dmc16.md
// "The reference firmware's behaviour"): every switch defaults to the spec's
// DMC-16; fixtures/profiles/dmc-lite.json sets them as Dragonframe's
// reference firmware (dmc-lite) behaves. Each is a documented host-visible
// behaviour that hosts must tolerate, not a fault.
struct Dmc16Behaviour {
  // --- the line ---
  // The receive buffer: the largest frame (header + DATA + checksum) taken
  // whole. The spec's 1048 is a minimum; dmc-lite holds 2048, so a header
  // declaring Length 2000 waits for its data and check bytes instead of
  // being oversize (the decoder's buffer is a fixed kMaxReceiveBuffer bytes).
  uint32_t receive_buffer_bytes = 1048;
  // After a false "DF" fails its checksum (or declares an oversize Length,
  // or is given up at an idle gap) the scan resumes just after its 'D', so a
  // real frame inside it is still found (spec). false: the bytes of the
  // candidate read so far are dropped (dmc-lite).
  bool rescan_after_bad_frame = true;

  // --- answers ---
  // MSG_MOTOR_MOVE answered with its MSG_MOTOR_MOVE response (spec); false:
  // an ACK OK (dmc-lite).
  bool move_response = true;
  // MSG_MOTOR_GET_POSITION answered with the positions under the request's ID
  // (spec); false: the positions go out as an unsolicited-style message with
  // ID 0, then an ACK OK carries the request's ID (dmc-lite).
  bool position_response = true;
  // MSG_GIO_IN sent as a request is answered with the inputs (spec); false:
  // ERR_UNSUPPORTED (dmc-lite).
  bool gio_in_request = true;
  // A host's ACK of a device message is taken silently (ERRATA 1.9); false:
  // answered ERR_UNSUPPORTED like any message the device does not take
  // as a request (dmc-lite).
  bool host_acks_silent = true;
  // MOTOR_JOG SPEED outside 1..10000 refused with ERR_RANGE (spec); false:
  // accepted, 0 and 10001 included (dmc-lite), 0 jogging as 1 and anything
  // above 10000 as 10000.
  bool jog_speed_checked = true;

  // --- motion ---
  // A motor that is not enabled (MSG_MOTOR_CONFIGURE flag 0x01) refuses
  // MOVE and JOG with ERR_GENERAL and sits out playback (spec reading); with
  // this, it takes MOVE, JOG and a SHOOT_FRAME that lists it and stays where
  // it is, as it does for uploads and POSITION_FRAME (dmc-lite, whose motors
  // start disabled: set motion.motors_enabled false with it).
  bool disabled_motors_ignore_motion = false;
  // Soft limits refuse MOVE and JOG beyond them (spec reading); false: they
  // bound only RUN_MOVE pre/post-roll and the stop deceleration (dmc-lite).
  bool soft_limits_bound_moves = true;
  // RT_GO this long after the motors came to rest answers
  // ERR_NOT_IN_POSITION while the device arms (dmc-lite: 40-60 ms).
  uint32_t arming_ms = 0;
  // STOP_ALL (no flags) while moving sets a hard-stop state: every command
  // from MSG_MOTOR_MOVE (0x0031) up except MOTOR_GET_POSITION is refused
  // with ERR_HARD_LOW, a second STOP_ALL included, until this long after
  // that STOP_ALL and the motors still (dmc-lite: 100 velocity updates of
  // 20 ms counted from the STOP_ALL). 0: none.
  uint32_t stop_all_lockout_ms = 0;
  // STOP_ALL brakes each motor at the larger of its max acceleration and its
  // speed per this many ms, so no stop lasts longer (dmc-lite: 1000, "let's
  // hard stop here": its deceleration raised to |velocity| per second).
  // 0: the max acceleration alone.
  uint32_t stop_all_within_ms = 0;
  // A moving motor's position between steps is reported truncated toward
  // zero (dmc-lite truncates its float position); false: the nearest step.
  // At rest a motor reads its step either way.
  bool positions_truncate = false;

  // --- real-time ---
  // MOVE TIME of position updates during pre-roll: the start frame's (0 for
  // frame 0) when true (dmc-lite); otherwise as docs/protocol-notes.md says.
  bool preroll_move_time_is_start_frame = false;
  // RT_END when the post-roll has ended (spec); true: at the last frame, no
  // wait for the post-roll (dmc-lite).
  bool rt_end_at_last_frame = false;
  // RT_END after SHOOT_FRAME / SHOOT_FRAME2 go-motion (spec); false: none (dmc-lite).
  bool rt_end_after_shot = true;

  // --- how requests are read and answered (docs/devices/dmc16.md) ---
  enum class LengthChecks : uint8_t {
    // Data shorter than a request's layout is ERR_GENERAL; bytes after it
    // are ignored (docs/protocol-notes.md "Trailing bytes").
    kSpec,
    // MOTOR_MOVE and MOTOR_RESET_POSITION are ERR_GENERAL unless their data
    // is exactly 5 bytes; every other request is carried out whatever its
    // length, a field its data lacks (or holds only part of) reading as 0,
    // and the fields after it too (dmc-lite).
    kMoveAndResetOnly,
  };
  LengthChecks length_checks = LengthChecks::kSpec;
  // MOTOR_SET_SPEED MAX VELOCITY or MAX ACCEL 0 refused with ERR_RANGE
  // (spec reading); false: taken, a MAX VELOCITY under 10 as 10 steps/s and
  // a MAX ACCEL of 0 as half the max velocity (dmc-lite).
  bool set_speed_checked = true;
  // RESET_POSITION's confirming MOTOR_GET_POSITION goes after its ACK
  // ("after ... responding", spec); kBeforeAck: before it, and a MOTOR_MOVE
  // to the step a resting motor stands on sends the positions before its
  // answer too (dmc-lite).
  enum class PositionConfirm : uint8_t { kAfterAck, kBeforeAck };
  PositionConfirm position_confirm = PositionConfirm::kAfterAck;
  // MOTOR_JOG SPEED: 1 = 1 % of the max velocity and acceleration, 10000 =
  // 100 %, linear between (spec); kPer10000: both times SPEED/10000, each at
  // least 4 (steps/s, steps/s^2), with no upper bound (dmc-lite).
  enum class JogSpeedScale : uint8_t { kSpec, kPer10000 };
  JogSpeedScale jog_speed_scale = JogSpeedScale::kSpec;
  // 0: a MOTOR_JOG goes on to its DESTINATION (spec). n: no further than
  // where, speeding up towards the jog velocity for at most n ms (keeping it
  // for the rest of them), it would brake to rest, so a host keeps jogging by
  // repeating the message; a JOG against the present motion only stops the
  // motor (dmc-lite: 500).
  uint32_t jog_horizon_ms = 0;
  // MOTOR_CONFIGURE coupling flags (0x10, 0x20 reversed): the flagged motor
  // follows the motor before it and reports the steps it makes (this
  // project's reading); kDrivesNext: the flagged motor drives the motor after
  // it (unless it is itself driven), whose reported position stays as it was
  // (dmc-lite).
  enum class Coupling : uint8_t { kFollowsPrevious, kDrivesNext };
  Coupling coupling = Coupling::kFollowsPrevious;
  // --- the real-time engine (docs/devices/dmc16.md "The 20 ms velocity tick") ---
  // 0: live runs play the frame path in continuous time and reports go out as
  // they fall due (spec reading). n: the device computes its motion every n ms
  // (dmc-lite: 20) and a live run is that tick's state machine: pre-roll ramp,
  // frame clock from START FRAME to END FRAME + 1 with MOVE TIME sampled on the
  // tick, post-roll ramp, then a move back onto frame END FRAME + 1 (or the
  // next loop pass); POSITION_FRAME moves take at least 2 x 0.5 s; position
  // updates are decided on the tick (a new frame, a stop, or 50 ms since the last).
  uint32_t playback_tick_ms = 0;
  // With a tick: the clock's frame f reads upload frame START FRAME + f - 1
  // (the upload stored from index 1 + (frame - START FRAME), read at the raw
  // frame number; dmc-lite). false: frame f reads upload frame f.
  bool upload_index_from_start_frame = false;
  // POSITION_FRAME outside the upload goes to the nearest uploaded frame and
  // answers OK (dmc-lite); false: ERR_RANGE.
  bool position_frame_clamped = false;
  // RT_END when a stop (STOP_ALL, MOTOR_STOP, a limit, the e-stop) ends a live
  // run or a shot (spec reading); false: none (dmc-lite).
  bool rt_end_after_stop = true;
  // RT_UPLOAD_MOVE_TRIGGERS with a frame index past the upload refused with
  // ERR_RANGE (spec reading); false: the point is dropped, ACK OK (dmc-lite).
  bool trigger_frames_checked = true;
  // RUN_MOVE stills angles past 360, or CLOSE not above OPEN, refused with
  // ERR_RANGE (spec reading); false: taken (dmc-lite: CLOSE <= OPEN exposes
  // 90 to 180 degrees, an angle past 360 holds the shutter to the frame's end).
  bool camera_angles_checked = true;
  // A 0 ms PRE-ROLL TIME makes the pre-roll position not a number: RUN_MOVE
  // answers ERR_PREROLL when a motor with an enabled lower soft limit would
  // move (dmc-lite natively; its ramp divides by the time). false: no ramp.
  bool zero_preroll_nan = false;
  // Unprompted messages (HI at power-on, position updates, RT_END, GIO_IN,
  // MOTOR_HARD_STOP) carry ID 0 (dmc-lite); false: a device-side sequence ID
  // (ERRATA 1.9).
  bool unsolicited_id_zero = false;
  // RESET_POSITION refused with ERR_MOVING while any motor moves (dmc-lite
  // checks its one moving flag); false: only while the motor named moves.
  bool reset_refused_while_any_moves = false;
  // MSG_MOTOR_HARD_STOP from the host hard-stops every motor (ACK OK; the
  // spec lists it among the motor commands); false: answered ERR_UNSUPPORTED
  // (dmc-lite only sends it).
  bool host_hard_stop = true;
};

struct Dmc16Profile {
  std::string name = "DMC-16";  // <= 32 bytes UTF-8 (HI NAME)
  uint8_t fw_major = 2;
  uint8_t fw_minor = 2;
  uint8_t fw_rev = 0;
  uint8_t motor_count = 16;     // 0..32
  uint16_t dmx_channels = 512;  // 0..512
  uint8_t gio_outputs = 8;      // 0..32
  uint8_t gio_inputs = 8;       // 0..32
  uint8_t hw_limit_sets = 16;   // 0..32
  uint32_t upload_frame_count = 10000;
  // Real-time moves, go-motion 1 and 2, couple motors, looping, camera
  // trigger. The virtual modes (0x003c) and the aim point (0x0040) come from
  // `virtual_axes` instead.
  uint32_t capabilities = 0x0783;
  Dmc16Virtual virtual_axes;
  Dmc16PhysicalRig physical_rig;
  // HI PROTOCOL VERSION; nullopt sends the 49-byte HI of older devices (FACTS).
  std::optional<uint16_t> protocol_version = 2;
  dmc::AckWidth ack_width = dmc::AckWidth::k16;
  uint32_t baud = dmc::kBaudRate;
  // The USB serial bridge to the host. No bridge (bytes as the UART at
  // `baud` completes them): the DMC-16's own bridge has not been measured.
  // dmc-lite's GIGA is CDC (FACTS "DMC v2"), which its profile sets.
  UsbBridge usb_bridge = UsbBridge::None();

  // Unsolicited MOTOR_GET_POSITION cadence while anything moves (spec: "about
  // every 0.10 seconds"; dmc-lite uses 50 ms).
  uint32_t position_report_interval_ms = 100;
  // A second STOP_ALL within this window hard-stops (MSG_MOTOR_STOP_ALL); 0:
  // none ever does (dmc-lite: a motor already stopping keeps its deceleration).
  uint32_t hard_stop_window_ms = 1000;
  uint32_t gio_debounce_ms = 20;
  double dmx_ramp_rate_per_s = 255;  // MSG_DMX RAMP=1 speed, value units per second

  // Motion defaults until MSG_MOTOR_SET_SPEED.
  double max_velocity_steps_per_s = 5000;
  double max_accel_steps_per_s2 = 10000;
  double hard_stop_multiple = 4;
  // Motors start enabled and blur-enabled (as after MSG_MOTOR_CONFIGURE
  // FLAGS 0x03) at power-on; false: neither (as dmc-lite's).
  bool motors_enabled = true;
  std::vector<Dmc16LimitSet> limit_sets;
  // Departures from the spec's reading (all off by default).
  Dmc16Behaviour behaviour;

  // The HI response this profile advertises.
  dmc::HiResponse Hi() const;
  // CAPABILITIES as advertised: `capabilities` plus the virtual bits when enabled.
  uint32_t Advertised() const {
    return capabilities | (virtual_axes.enabled ? virtual_axes.capabilities : 0u);
  }
  bool Has(uint32_t capability) const { return (Advertised() & capability) != 0; }
};

// Reads a profile object; absent fields keep the defaults above. Throws
// ProfileError naming the field and the fix. `where` prefixes messages.
// `base_dir` is where relative file names in the profile (physical_rig.rig)
// are looked up first; the working directory comes next.
Dmc16Profile Dmc16ProfileFromJson(const nlohmann::json& j, const std::string& where,
                                  const std::string& base_dir = "");
// Reads a profile file. Throws ProfileError (unreadable file, bad JSON, bad field).
Dmc16Profile LoadDmc16Profile(const std::string& path);
// The profile as JSON (every field), for State() and for writing a template.
nlohmann::json Dmc16ProfileToJson(const Dmc16Profile& p);

}  // namespace moco::devices

#endif  // MOCO_DEVICES_DMC16_DMC16_PROFILE_H_
