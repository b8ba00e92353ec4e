// What the DMC v2 case files share (dmc_cases.cpp and dmc_cases_*.cpp): the
// checks every case makes and the cases of the other files that the case
// table in dmc_cases.cpp lists (their waits are in dmc_timing.h). Internal to
// the DMC v2 suites.
#ifndef MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_CASES_INTERNAL_H_
#define MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_CASES_INTERNAL_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "conformance/protocols/dmc/dmc_suites.h"
#include "conformance/protocols/dmc/dmc_timing.h"

namespace moco::conformance::dmc_cases {

// Evidence at record `r` (or at the host's time when there is none).
Evidence EvOf(const DmcHost& h, const DmcRecord* r, std::string expected, std::string observed);
// "ACK ERR_RANGE", or what the record is.
std::string CodeText(const DmcRecord* r);
// `rule` passes when `r` is an ACK with `want`.
bool ExpectCode(DmcCaseContext& c, std::string_view rule, const DmcRecord* r, dmc::AckCode want);
// `rule` and DMC-ACK-011 pass when `r` is ACK OK.
bool ExpectOk(DmcCaseContext& c, std::string_view rule, const DmcRecord* r);
// `rule` passes when `r` is an ACK other than OK.
bool ExpectRefused(DmcCaseContext& c, std::string_view rule, const DmcRecord* r);
bool Expect(DmcCaseContext& c, std::string_view rule, bool ok, std::string expected,
            std::string observed);

struct Update {
  TimeNs t_ns;
  uint32_t move_time;
  std::vector<int32_t> positions;
  const DmcRecord* rec;
};
// Unsolicited MOTOR_GET_POSITION messages from record `from` on.
std::vector<Update> UpdatesSince(const DmcHost& h, size_t from);
// Unsolicited messages of `type` from record `from` on.
int CountSince(const DmcHost& h, size_t from, dmc::MsgType type);
bool IsUnsolicited(const DmcRecord& r, dmc::MsgType type);
// "[1, 2, 3]".
std::string Vec(const std::vector<int32_t>& v);
// v[i], or 0 past its end.
int32_t At(const std::vector<int32_t>& v, size_t i);
// Whether the device puts `motor` (index) where `ok` wants it by its own
// account: its answer to MOTOR_GET_POSITION, or its last position update from
// record `from` on. A fault in one of the two reports then fails that report's
// rule (DMC-POS-006, DMC-POS-004) instead of every rule judged on where a
// motor rests.
bool ReportsAt(const DmcHost& h, size_t from, const std::optional<std::vector<int32_t>>& answer,
               size_t motor, const std::function<bool(int32_t)>& ok);

// Whether `r` accepts a MOTOR_MOVE: the MOTOR_MOVE response, or an ACK OK
// from a device that answers moves that way (the reference firmware does;
// DMC-ACK-008 judges that form once, the cases judge the motion).
bool MoveAccepted(const DmcRecord* r);
// MSG_RT_GO for an armed run or shot ("When the device has stopped moving, a
// MSG_RT_GO command will perform the run or shoot of the frame"). A device
// still arming answers ERR_NOT_IN_POSITION: the host retries every
// kArmingRetryNs (10 ms) for up to kArmingLimitNs (1 s), DMC-RT-015 judges
// the delay, and the last answer is returned for the case's own rule.
const DmcRecord* Go(DmcCaseContext& c);

// Moves `motor` to `to` and waits until nothing moves.
void MoveAndRest(DmcCaseContext& c, uint8_t motor, int32_t to);

// --- the motor and limit cases (dmc_cases_motor.cpp)
void Move(DmcCaseContext& c);
void Stop(DmcCaseContext& c);
void StopAll(DmcCaseContext& c);
void HardStop(DmcCaseContext& c);
void Reset(DmcCaseContext& c);
void Configure(DmcCaseContext& c);
void JogSpeeds(DmcCaseContext& c);
void Couple(DmcCaseContext& c);
void NoHostAck(DmcCaseContext& c);
void EStop(DmcCaseContext& c);
void SoftLimits(DmcCaseContext& c);
void HardLimit(DmcCaseContext& c);

// --- the error cases (dmc_cases_errors.cpp)
void BadMotor(DmcCaseContext& c);
void Checksum(DmcCaseContext& c);
void UnknownType(DmcCaseContext& c);
void BadLength(DmcCaseContext& c);
void Noise(DmcCaseContext& c);
void MaxFrame(DmcCaseContext& c);
void Unadvertised(DmcCaseContext& c);

// --- the general I/O and DMX cases (dmc_cases_io.cpp)
void Io(DmcCaseContext& c);
void Dmx(DmcCaseContext& c);
void GioInputChange(DmcCaseContext& c);

// --- the real-time uploads and runs the cases share (dmc_cases_rt.cpp)
struct Uploaded {
  std::vector<std::vector<int32_t>> path;  // [motor-1][frame]: positions at frames 0..end
  uint32_t end = 0;
};
// Uploads frames 0..20 (fewer when the device holds fewer): motor 1 climbs 40
// steps a frame and motor 2 falls 25 a frame over frames 0..10, then both
// hold. `more` sends further sections (DMX, triggers) before
// UPLOAD_MOVE_END; every ACK is judged by DMC-RT-001. Nullopt when the
// positions cannot be read.
std::optional<Uploaded> Upload(DmcCaseContext& c,
                               const std::function<void(uint32_t end)>& more = {});
// RT_POSITION_FRAME `frame` (judged by `rule`), then the rig at rest on it.
bool AtFrame(DmcCaseContext& c, const Uploaded& u, uint32_t frame, std::string_view rule);
// RT_RUN_MOVE of frames 0..end at 24 fps, 500 ms pre- and post-roll, in the
// 29-byte form (no FLAGS, no camera angles).
dmc::RtRunMove ShortRun(uint32_t end);

// --- the real-time, go-motion, looping and virtual-axis cases (dmc_cases_rt.cpp)
void UploadPosition(DmcCaseContext& c);
void LiveRun(DmcCaseContext& c);
void StopRun(DmcCaseContext& c);
void GoUnarmed(DmcCaseContext& c);
void JogAll(DmcCaseContext& c);
void Shoot(DmcCaseContext& c, bool second);
void StopLoop(DmcCaseContext& c);
void VirtPosition(DmcCaseContext& c);
void VirtConfigForms(DmcCaseContext& c);
void VirtMoveReadBack(DmcCaseContext& c);
void VirtStopShort(DmcCaseContext& c);
void VirtJogs(DmcCaseContext& c);
void VirtAim(DmcCaseContext& c);

// --- the real-time outputs: DMX, triggers, bloop, camera, pre-/post-roll
// (dmc_cases_rt_io.cpp)
void UploadDmx(DmcCaseContext& c);
void SyncRun(DmcCaseContext& c);
void Triggers(DmcCaseContext& c);
void CameraStills(DmcCaseContext& c);
void CameraVideo(DmcCaseContext& c);
void RollLimits(DmcCaseContext& c);

}  // namespace moco::conformance::dmc_cases

#endif  // MOCO_CONFORMANCE_PROTOCOLS_DMC_DMC_CASES_INTERNAL_H_
