// StackShot 3X settings, NVM, stack and curve cases (stackshot-protocol.txt
// 1.1.3-1.1.9, 1.1.16-1.1.20; ERRATA stackshot 2-5, 10; FACTS "StackShot"):
// each reads what is there, changes it, checks the change and puts it back.
// Listed by the table in stackshot_cases.cpp.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <limits>
#include <set>
#include <vector>

#include "base/format.h"
#include "conformance/protocols/stackshot/stackshot_cases_internal.h"
#include "conformance/protocols/stackshot/stackshot_timing.h"
#include "devices/stackshot3x/stackshot3x.h"

namespace moco::conformance::ss_cases {

using stackshot::Action;
using stackshot::Command;
using stackshot::Units;

// ---------------------------------------------------------------- config

// Reads a setting; the reply's payload or nullopt.
std::optional<stackshot::Payload> ReadSetting(SsHost& h, Command cmd, uint8_t axis = 0,
                                              bool sub = false,
                                              stackshot::Payload query = stackshot::Empty{}) {
  const SsRecord* r = h.Call(SsRead(cmd, std::move(query), axis, sub));
  if (StatusOf(r) != Action::kRspOk || !r->reply) return std::nullopt;
  return r->reply->payload;
}

std::string Text(const std::optional<stackshot::Payload>& p, uint16_t cmd) {
  if (!p) return "no value";
  stackshot::DeviceReply r;
  r.command = cmd;
  r.kind = stackshot::ReplyKind::kReadResponse;
  r.payload = *p;
  return stackshot::Describe(r);
}

// Writes `value`, reads it back (SS-CFG-001) and puts the old value back.
void RoundTrip(SsCaseContext& c, Command cmd, const stackshot::Payload& value, uint8_t axis = 0,
               bool sub = false) {
  SsHost& h = c.host;
  const auto old = ReadSetting(h, cmd, axis, sub);
  if (!old) {
    Expect(c, "SS-CFG-001", false, stackshot::CommandName(stackshot::Id(cmd)) + " readable",
           "no value");
    return;
  }
  ExpectOk(c, "SS-CFG-001", h.Call(SsWrite(cmd, value, axis, sub)));
  const auto now = ReadSetting(h, cmd, axis, sub);
  Expect(c, "SS-CFG-001", now && *now == value, Text(value, stackshot::Id(cmd)),
         Text(now, stackshot::Id(cmd)));
  h.Call(SsWrite(cmd, *old, axis, sub));
}

void ConfigValuesCase(SsCaseContext& c) {
  using stackshot::EnumValue;
  RoundTrip(c, Command::kRailConfigBacklight, stackshot::U8Value{7});
  RoundTrip(c, Command::kRailConfigTorque, stackshot::U8Value{4});
  RoundTrip(c, Command::kRailConfigHoldingTorque, stackshot::U8Value{0});
  RoundTrip(c, Command::kRailConfigMode,
            EnumValue<stackshot::RailMode>{stackshot::RailMode::kManual});
  RoundTrip(c, Command::kRailConfigUnits, EnumValue<Units>{Units::kMils});
  RoundTrip(c, Command::kRailConfigNumSteps, stackshot::U16Value{321});
  RoundTrip(c, Command::kRailConfigNumPulses, stackshot::U16Value{3});
  RoundTrip(c, Command::kRailConfigSettleTime, stackshot::F32Value{1.25f});
  RoundTrip(c, Command::kRailConfigOffTime, stackshot::F32Value{0.75f}, 0, true);
  RoundTrip(c, Command::kRailConfigPulseTime, stackshot::F32Value{0.125f});
  RoundTrip(c, Command::kRailConfigTimelapse, stackshot::F32Value{60.0f});
  RoundTrip(c, Command::kRailConfigRampTime, stackshot::F32Value{0.5f});
  RoundTrip(c, Command::kRailConfigShutterDisable, stackshot::BoolValue{true});
  RoundTrip(c, Command::kRailConfigAutoReturn, stackshot::BoolValue{true});
  RoundTrip(c, Command::kRailConfigToffFinal, stackshot::BoolValue{false});
  RoundTrip(c, Command::kRailConfigPolarity, stackshot::BoolValue{true});
  RoundTrip(c, Command::kRailConfigRotaryBacklash, stackshot::F32Value{2.5f});
  RoundTrip(c, Command::kRailConfigRotaryRatio, stackshot::F32Value{90.0f});
  RoundTrip(c, Command::kRailConfigRotaryDegrees, stackshot::F32Value{15.0f});
  RoundTrip(c, Command::kRailConfigGlobalMode,
            EnumValue<stackshot::GlobalMode>{stackshot::GlobalMode::kPano1x});
  RoundTrip(c, Command::kRailConfigShutter,
            EnumValue<stackshot::ShutterSetting>{stackshot::ShutterSetting::kBoth});
  RoundTrip(c, Command::kRailConfigIoMode,
            EnumValue<stackshot::IoMode>{stackshot::IoMode::kMaster});
}

// Writes a bad value: SS-CFG-002 (or `rule`) wants BAD_PARAM and the value unchanged.
void Refuse(SsCaseContext& c, std::string_view rule, Command cmd, const stackshot::Payload& bad,
            uint8_t axis = 0, stackshot::Payload query = stackshot::Empty{}) {
  SsHost& h = c.host;
  const auto old = ReadSetting(h, cmd, axis, false, query);
  ExpectStatus(c, rule, h.Call(SsWrite(cmd, bad, axis)), Action::kBadParam);
  const auto now = ReadSetting(h, cmd, axis, false, query);
  Expect(c, rule, old.has_value() && now == old, Text(old, stackshot::Id(cmd)) + " kept",
         Text(now, stackshot::Id(cmd)));
}

void ConfigRangesCase(SsCaseContext& c) {
  using stackshot::EnumValue;
  for (uint8_t v : std::initializer_list<uint8_t>{0, 11, 200}) {
    Refuse(c, "SS-CFG-002", Command::kRailConfigBacklight, stackshot::U8Value{v});
    Refuse(c, "SS-CFG-002", Command::kRailConfigTorque, stackshot::U8Value{v});
  }
  Refuse(c, "SS-CFG-002", Command::kRailConfigHoldingTorque, stackshot::U8Value{11});
  Refuse(c, "SS-CFG-002", Command::kRailConfigUnits, EnumValue<Units>{static_cast<Units>(3)});
  Refuse(c, "SS-CFG-002", Command::kRailConfigMode,
         EnumValue<stackshot::RailMode>{static_cast<stackshot::RailMode>(8)});
  Refuse(c, "SS-CFG-002", Command::kRailConfigGlobalMode,
         EnumValue<stackshot::GlobalMode>{static_cast<stackshot::GlobalMode>(13)});
  Refuse(c, "SS-CFG-002", Command::kRailConfigShutter,
         EnumValue<stackshot::ShutterSetting>{static_cast<stackshot::ShutterSetting>(4)});
  // Negative and non-finite values.
  const stackshot::UnitsQuery mm{Units::kMm};
  Refuse(c, "SS-CFG-004", Command::kRailConfigTotalDistance, stackshot::UnitsF32{Units::kMm, -1.0f},
         0, mm);
  Refuse(c, "SS-CFG-004", Command::kRailConfigSpeed,
         stackshot::UnitsF32{Units::kMm, std::numeric_limits<float>::quiet_NaN()}, 0, mm);
  Refuse(c, "SS-CFG-004", Command::kRailConfigBacklash, stackshot::UnitsF32{Units::kMm, -0.5f}, 0,
         mm);
  Refuse(c, "SS-CFG-004", Command::kRailConfigSettleTime, stackshot::F32Value{-1.0f});
  Refuse(c, "SS-CFG-004", Command::kRailConfigRampTime,
         stackshot::F32Value{std::numeric_limits<float>::infinity()});
}

void ConfigUnitsCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const struct {
    Command cmd;
    float mm;
  } cases[] = {{Command::kRailConfigBacklash, 0.25f},
               {Command::kRailConfigSpeed, 1.5f},
               {Command::kRailConfigTotalDistance, 12.5f},
               {Command::kRailConfigDistancePerStep, 0.05f}};
  for (const auto& k : cases) {
    const auto old = ReadSetting(h, k.cmd, 0, false, stackshot::UnitsQuery{Units::kMm});
    ExpectOk(c, "SS-CFG-003", h.Call(SsWrite(k.cmd, stackshot::UnitsF32{Units::kMm, k.mm})));
    const auto in_mm = ReadSetting(h, k.cmd, 0, false, stackshot::UnitsQuery{Units::kMm});
    const auto in_mils = ReadSetting(h, k.cmd, 0, false, stackshot::UnitsQuery{Units::kMils});
    const auto* a = in_mm ? std::get_if<stackshot::UnitsF32>(&*in_mm) : nullptr;
    const auto* b = in_mils ? std::get_if<stackshot::UnitsF32>(&*in_mils) : nullptr;
    const double want_mils = k.mm / 0.0254;
    Expect(c, "SS-CFG-003",
           a != nullptr && std::fabs(a->value.value() - k.mm) <= 1e-5 * k.mm && b != nullptr &&
               std::fabs(b->value.value() - want_mils) <= 1e-4 * want_mils,
           stackshot::FormatF32(k.mm) + " mm = " + std::to_string(want_mils) + " mils",
           Text(in_mm, stackshot::Id(k.cmd)) + "; " + Text(in_mils, stackshot::Id(k.cmd)));
    if (old) h.Call(SsWrite(k.cmd, *old));
  }
}

void NameCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto old = ReadSetting(h, Command::kRailConfigName);
  ExpectOk(c, "SS-CFG-005",
           h.Call(SsWrite(Command::kRailConfigName, stackshot::Text{"mococheck", true})));
  const auto now = ReadSetting(h, Command::kRailConfigName);
  const auto* t = now ? std::get_if<stackshot::Text>(&*now) : nullptr;
  Expect(c, "SS-CFG-005", t != nullptr && t->text == "mococheck" && t->terminated,
         "\"mococheck\" NUL-terminated", Text(now, stackshot::Id(Command::kRailConfigName)));
  const auto* o = old ? std::get_if<stackshot::Text>(&*old) : nullptr;
  // "On read, 0xFF indicates power-on / last saved configuration": no name.
  const std::string restore = o == nullptr || o->text == "\xff" ? "" : o->text;
  h.Call(SsWrite(Command::kRailConfigName, stackshot::Text{restore, true}));
}

std::optional<uint8_t> Backlight(SsHost& h) {
  const auto v = ReadSetting(h, Command::kRailConfigBacklight);
  const auto* u = v ? std::get_if<stackshot::U8Value>(&*v) : nullptr;
  if (u == nullptr) return std::nullopt;
  return u->value;
}

void SlotsCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto b0 = Backlight(h);
  if (!b0) return;
  ExpectRefused(c, "SS-SLOT-002",
                h.Call(SsWrite(Command::kRailConfigLoad, stackshot::U8Value{11})));
  if (c.target.CanRestart()) {
    // A restartable target starts with empty slots, and only slot 4 and 0 are saved here.
    ExpectRefused(c, "SS-SLOT-002",
                  h.Call(SsWrite(Command::kRailConfigLoad, stackshot::U8Value{7})));
  }
  auto b = Backlight(h);
  Expect(c, "SS-SLOT-002", b == b0, "backlight " + std::to_string(*b0) + " kept",
         b ? std::to_string(*b) : "none");
  const uint8_t saved = *b0 == 3 ? 4 : 3, changed = saved == 8 ? 9 : 8;
  h.Call(SsWrite(Command::kRailConfigBacklight, stackshot::U8Value{saved}));
  ExpectOk(c, "SS-SLOT-001", h.Call(SsWrite(Command::kRailConfigSave, stackshot::U8Value{4})));
  h.Call(SsWrite(Command::kRailConfigBacklight, stackshot::U8Value{changed}));
  ExpectOk(c, "SS-SLOT-001", h.Call(SsWrite(Command::kRailConfigLoad, stackshot::U8Value{4})));
  b = Backlight(h);
  Expect(c, "SS-SLOT-001", b == saved, "backlight " + std::to_string(saved) + " from slot 4",
         b ? std::to_string(*b) : "none");
  h.Call(SsWrite(Command::kRailConfigBacklight, stackshot::U8Value{*b0}));
}

// CC_RESET, then waits for the controller to answer PING again.
bool ResetAndWait(SsCaseContext& c) {
  SsHost& h = c.host;
  ExpectOk(c, "SS-RESET-001", h.Call(SsWrite(Command::kReset)));
  for (int i = 0; i < 20; ++i) {
    h.Idle(kResetPingPauseNs);
    const SsRecord* r = h.Call(SsRead(Command::kPing, stackshot::PingRequest{0x42}));
    if (StatusOf(r) == Action::kRspOk) {
      c.v.Pass("SS-RESET-001");
      return true;
    }
  }
  Expect(c, "SS-RESET-001", false, "PING answered within 2 s of CC_RESET", "no answer");
  return false;
}

void PowerOnConfigCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const auto b0 = Backlight(h);
  if (!b0) return;
  const uint8_t power_on = *b0 == 2 ? 6 : 2, unsaved = power_on == 9 ? 10 : 9;
  h.Call(SsWrite(Command::kRailConfigBacklight, stackshot::U8Value{power_on}));
  ExpectOk(c, "SS-SLOT-003", h.Call(SsWrite(Command::kRailConfigSave, stackshot::U8Value{0})));
  h.Call(SsWrite(Command::kRailConfigBacklight, stackshot::U8Value{unsaved}));
  if (!ResetAndWait(c)) return;
  const auto b = Backlight(h);
  Expect(c, "SS-SLOT-003", b == power_on,
         "backlight " + std::to_string(power_on) + " (saved to slot 0)",
         b ? std::to_string(*b) : "none");
  Expect(c, "SS-RESET-002", b != unsaved,
         "the unsaved backlight " + std::to_string(unsaved) + " gone",
         b ? std::to_string(*b) : "none");
  h.Call(SsWrite(Command::kRailConfigBacklight, stackshot::U8Value{*b0}));
  h.Call(SsWrite(Command::kRailConfigSave, stackshot::U8Value{0}));
}

// ---------------------------------------------------------------- nvm

std::optional<uint32_t> ReadNvm(SsHost& h, uint8_t reg) {
  const auto* v =
      PayloadOf<stackshot::U32Value>(h.Call(SsRead(Command::kNvmAccess, stackshot::NvmRead{reg})));
  if (v == nullptr) return std::nullopt;
  return v->value;
}

std::optional<uint32_t> ReadSerial(SsHost& h) {
  const auto* v = PayloadOf<stackshot::U32Value>(h.Call(SsRead(Command::kSerialNumber)));
  if (v == nullptr) return std::nullopt;
  return v->value;
}

std::string Hex32(std::optional<uint32_t> v) { return v ? base::Hex(*v, 8) : "no value"; }

void NvmRegistersCase(SsCaseContext& c) {
  SsHost& h = c.host;
  for (uint8_t reg : std::initializer_list<uint8_t>{5, 31}) {
    const auto old = ReadNvm(h, reg);
    if (!old) continue;
    const uint32_t value = 0x12345600u + reg;
    ExpectOk(c, "SS-NVM-001",
             h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{reg, value})));
    const auto now = ReadNvm(h, reg);
    Expect(c, "SS-NVM-001", now == value, Hex32(value), Hex32(now));
    h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{reg, *old}));
  }
  for (uint8_t reg : std::initializer_list<uint8_t>{128, 200, 255}) {
    ExpectStatus(c, "SS-NVM-002", h.Call(SsRead(Command::kNvmAccess, stackshot::NvmRead{reg})),
                 Action::kBadParam);
    ExpectStatus(c, "SS-NVM-002", h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{reg, 1})),
                 Action::kBadParam);
  }
  const SsRecord* r = h.Call(SsRead(Command::kNvmAccess, stackshot::NvmRead{40}));
  c.v.Check("SS-NVM-005", StatusOf(r) == Action::kRspOk,
            [&] { return EvOf(h, r, "register 40 readable (0-127)", Show(r)); });
  // Register 0 is the axis identifier.
  const auto reg0 = ReadNvm(h, 0);
  if (!reg0) return;
  ExpectOk(c, "SS-NVM-004", h.Call(SsWrite(Command::kRailConfigAxis, stackshot::U8Value{2})));
  auto now = ReadNvm(h, 0);
  Expect(c, "SS-NVM-004", now && (*now & 0xff) == 2, "register 0 = 2 after CC_RAIL_CONFIG_AXIS 2",
         Hex32(now));
  h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{0, 3}));
  const auto axis = ReadSetting(h, Command::kRailConfigAxis);
  const auto* a = axis ? std::get_if<stackshot::U8Value>(&*axis) : nullptr;
  Expect(c, "SS-NVM-004", a != nullptr && a->value == 3,
         "CC_RAIL_CONFIG_AXIS 3 after register 0 = 3",
         Text(axis, stackshot::Id(Command::kRailConfigAxis)));
  h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{0, *reg0}));
}

void SerialCase(SsCaseContext& c) {
  SsHost& h = c.host;
  auto serial = ReadSerial(h);
  if (!serial) return;
  if (*serial == stackshot::kUnprogrammed) {
    if (!c.target.CanRestart()) {
      c.log.push_back(
          "the serial number is unprogrammed and a write would be permanent on this "
          "device: the write-once checks are not exercised");
      return;
    }
    const uint32_t first = 31415926;
    ExpectOk(c, "SS-SERIAL-004",
             h.Call(SsWrite(Command::kSerialNumber, stackshot::U32Value{first})));
    serial = ReadSerial(h);
    Expect(c, "SS-SERIAL-004", serial == first, Hex32(first), Hex32(serial));
    if (!serial) return;
  }
  const uint32_t other = *serial ^ 0x00ff00ffu;
  const SsRecord* r = h.Call(SsWrite(Command::kSerialNumber, stackshot::U32Value{other}));
  ExpectRefused(c, "SS-SERIAL-001", r);
  if (StatusOf(r) && *StatusOf(r) != Action::kRspOk) {
    c.v.Check("SS-SERIAL-002", StatusOf(r) != Action::kNotEmpty,
              [&] { return EvOf(h, r, "failed (the CC_SERIAL_NUMBER table)", Show(r)); });
  }
  const auto after = ReadSerial(h);
  Expect(c, "SS-SERIAL-001", after == serial, "serial number still " + Hex32(serial), Hex32(after));
}

void NvmPersistCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const uint8_t reg = 6;
  const auto old = ReadNvm(h, reg);
  const auto serial = ReadSerial(h);
  if (!old || !serial) return;
  const uint32_t value = *old == 0xc0ffee00u ? 0xc0ffee01u : 0xc0ffee00u;
  ExpectOk(c, "SS-NVM-001", h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{reg, value})));
  if (!ResetAndWait(c)) return;
  auto now = ReadNvm(h, reg);
  Expect(c, "SS-NVM-003", now == value, Hex32(value) + " after CC_RESET", Hex32(now));
  auto s = ReadSerial(h);
  Expect(c, "SS-SERIAL-003", s == serial, Hex32(serial) + " after CC_RESET", Hex32(s));
  if (c.target.CanRestart()) {
    // A power cycle: a new host on the restarted target.
    c.host.Close();
    c.target.Restart();
    SsHost again(c.target, c.v, c.host_options, c.host.checksum());
    now = ReadNvm(again, reg);
    Expect(c, "SS-NVM-003", now == value, Hex32(value) + " after a power cycle", Hex32(now));
    s = ReadSerial(again);
    Expect(c, "SS-SERIAL-003", s == serial, Hex32(serial) + " after a power cycle", Hex32(s));
    again.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{reg, *old}));
    again.Close();
    return;
  }
  h.Call(SsWrite(Command::kNvmAccess, stackshot::NvmWrite{reg, *old}));
}

// ---------------------------------------------------------------- stack

// Sets a setting for the rest of the case; the write that puts the old value
// back goes into `undo`. False when the setting cannot be read.
bool SetForCase(SsHost& h, std::vector<stackshot::HostCommand>& undo, Command cmd,
                const stackshot::Payload& value, uint8_t axis = 0, bool sub = false) {
  const auto old = ReadSetting(h, cmd, axis, sub);
  if (!old) return false;
  undo.push_back(SsWrite(cmd, *old, axis, sub));
  h.Call(SsWrite(cmd, value, axis, sub));
  return true;
}

void Undo(SsHost& h, std::vector<stackshot::HostCommand>& undo) {
  for (auto it = undo.rbegin(); it != undo.rend(); ++it) h.Call(*it);
  undo.clear();
}

std::string Frames(const std::set<uint32_t>& frames) {
  if (frames.empty()) return "never";
  std::string s = "at stack position(s)";
  for (uint32_t f : frames) s += " " + std::to_string(f);
  return s;
}

void StackCase(SsCaseContext& c) {
  SsHost& h = c.host;
  SsWaitRest(h, Axes(c), kRestWaitNs);
  const auto p0 = SsPositionSteps(h, 0);
  if (!p0) return;
  // A stack step is a move, a pause "before activating the shutter"
  // (CC_RAIL_CONFIG_SETTLE_TIME) and the "Number of pulses (pictures to be
  // taken) applied at each step" (CC_RAIL_CONFIG_NUM_PULSES) on the shutter
  // the axis names ("For the specified axis, this value indicates which
  // shutter should be active", CC_RAIL_CONFIG_SHUTTER). The case fixes them
  // for X: shutter 1, one pulse of 0.3 s (long enough for 100 ms status polls
  // to see each one, "RAIL_STATUS_SHUTTER 0x02 The shutter is currently
  // firing", 1.1.6), and no "auto-return upon finishing a sequence"
  // (CC_RAIL_CONFIG_AUTO_RETURN), so that the stack ends on its end position.
  using stackshot::EnumValue;
  std::vector<stackshot::HostCommand> undo;
  const bool set =
      SetForCase(h, undo, Command::kRailConfigSettleTime, stackshot::F32Value{0.05f}) &&
      SetForCase(h, undo, Command::kRailConfigShutter,
                 EnumValue<stackshot::ShutterSetting>{stackshot::ShutterSetting::kShutter1}) &&
      SetForCase(h, undo, Command::kRailConfigShutterDisable, stackshot::BoolValue{false}) &&
      SetForCase(h, undo, Command::kRailConfigNumPulses, stackshot::U16Value{1}) &&
      SetForCase(h, undo, Command::kRailConfigPulseTime, stackshot::F32Value{0.3f}) &&
      SetForCase(h, undo, Command::kRailConfigAutoReturn, stackshot::BoolValue{false});
  if (!set) {
    c.log.push_back(
        "a stack setting (settle, shutter, pulses, auto-return) is unreadable: "
        "the stack is not run");
    Undo(h, undo);
    return;
  }
  stackshot::RailStack s;
  s.mode = 0;
  s.num_steps = 3;
  s.x_start = static_cast<uint32_t>(static_cast<int32_t>(*p0));
  s.x_end = static_cast<uint32_t>(static_cast<int32_t>(*p0 + 800));
  s.reserved = 0;
  ExpectOk(c, "SS-STACK-001", h.Call(SsWrite(Command::kRailStack, s)));
  const SsRecord* r = h.Call(SsRead(Command::kRailStackStatus));
  const auto* st = PayloadOf<stackshot::RailStatus>(r);
  Expect(c, "SS-STACK-001", st != nullptr && st->bits != 0, "STACK_STATUS running", Show(r));
  uint32_t frames = 0;
  std::set<uint32_t> fired;  // the stack positions at which the shutter was seen firing
  bool ended = false;
  for (const TimeNs until = h.Now() + kStackRunWaitNs; h.Now() < until && !h.link_lost();) {
    h.Idle(kSsStatusPollNs);
    // The count first: it does not change while the shutter fires.
    const auto* pos = PayloadOf<stackshot::U32Value>(h.Call(SsRead(Command::kRailStackPosition)));
    if (pos != nullptr) frames = std::max(frames, pos->value);
    const auto rail = SsRailStatus(h, 0);
    if (pos != nullptr && rail && (*rail & stackshot::kRailStatusShutter) != 0) {
      fired.insert(pos->value);
    }
    st = PayloadOf<stackshot::RailStatus>(h.Call(SsRead(Command::kRailStackStatus)));
    if (st != nullptr && st->bits == 0) {
      ended = true;
      break;
    }
  }
  if (const auto* pos = PayloadOf<stackshot::U32Value>(h.Call(SsRead(Command::kRailStackPosition))))
    frames = std::max(frames, pos->value);
  Expect(c, "SS-STACK-001", ended && frames == 3, "the stack ends after 3 frames",
         (ended ? "ended" : "still running") + std::string(" after ") + std::to_string(frames) +
             " frame(s)");
  // Each step takes its picture, and the rail travels from start to end.
  Expect(c, "SS-STACK-001", fired.size() == 3,
         "the shutter seen firing (CC_RAIL_STATUS SHUTTER) in each of the 3 frames",
         "seen firing " + Frames(fired));
  SsWaitRest(h, {0}, kRestWaitNs);
  const auto p1 = SsPositionSteps(h, 0);
  Expect(c, "SS-STACK-001", p1 && std::llabs(*p1 - (*p0 + 800)) <= 1,
         "the rail at rest on the X end position " + std::to_string(*p0 + 800) + " steps",
         Steps(p1));
  // A stack while an axis moves.
  h.Call(Move(0, 20000));
  ExpectStatus(c, "SS-STACK-002", h.Call(SsWrite(Command::kRailStack, s)), Action::kBusy);
  h.Call(SsWrite(Command::kRailStop));
  SsWaitRest(h, {0}, kRestWaitNs);
  Undo(h, undo);
  ReturnTo(c, 0, *p0);
}

// ---------------------------------------------------------------- curves

stackshot::MotionConfig Curve(float y0_mm, float dy_mm, float t_s) {
  stackshot::MotionConfig m;
  m.axis_type = stackshot::AxisType::kRail;
  m.curves[0].p = {stackshot::BezierPoint{0.0f, y0_mm},
                   {0.3f * t_s, y0_mm},
                   {0.7f * t_s, y0_mm + dy_mm},
                   {t_s, y0_mm + dy_mm}};
  return m;
}

std::optional<float> PositionMm(SsHost& h, uint8_t axis) {
  const auto* v = PayloadOf<stackshot::UnitsF32>(
      h.Call(SsRead(Command::kRailPositionCurrent, stackshot::UnitsQuery{Units::kMm}, axis)));
  if (v == nullptr) return std::nullopt;
  return v->value.value();
}

// The position on cubic Bezier `k` at time `t_s`: x(u) is the time and y(u)
// the position, u in 0..1 ("Motion paths in StackShot 3X are defined using
// cubic Bezier curves", 2 CC_MOTION_CONFIG; x in seconds from
// CC_MOTION_START, the reading docs/protocol-notes.md takes). x(u) rises with u for the
// curves this case sends (P0.x <= P1.x <= P2.x <= P3.x); t is clamped to the
// curve's time.
double CurveAt(const stackshot::BezierCurve& k, double t_s) {
  auto at = [](double a, double b, double c, double d, double u) {
    const double v = 1 - u;
    return v * v * v * a + 3 * v * v * u * b + 3 * v * u * u * c + u * u * u * d;
  };
  const auto& p = k.p;
  double lo = 0, hi = 1;
  for (int i = 0; i < 60; ++i) {
    const double u = (lo + hi) / 2;
    if (at(p[0].x.value(), p[1].x.value(), p[2].x.value(), p[3].x.value(), u) < t_s) {
      lo = u;
    } else {
      hi = u;
    }
  }
  return at(p[0].y.value(), p[1].y.value(), p[2].y.value(), p[3].y.value(), (lo + hi) / 2);
}

// CC_MOTION_START of X; once X rests, its position in mm.
std::optional<float> PlayX(SsCaseContext& c, std::string_view rule) {
  ExpectOk(c, rule,
           c.host.Call(SsWrite(Command::kMotionStart, stackshot::MotionStart{true, false, false})));
  c.host.Idle(kCurveStartNs);
  SsWaitRest(c.host, {0}, kRestWaitNs);
  return PositionMm(c.host, 0);
}

std::string Mm(std::optional<float> mm) {
  return mm ? stackshot::FormatF32(*mm) + " mm" : "no position";
}

// SS-CURVE-005: CC_MOTION_START plays `m` (one curve 0 rising over `t_s`
// seconds from where X rests) along its curve: each position read while it
// plays lies on the curve between the earliest and the latest time it can
// have been read at. The spline's time starts between the MOTION_START
// request and its reply, a reading is taken between its request and its
// reply; 0.05 mm to spare (a step, the float). Then X rests on the last
// keyframe.
void PlayAlongTheCurve(SsCaseContext& c, const stackshot::MotionConfig& m, double t_s) {
  SsHost& h = c.host;
  const stackshot::BezierCurve& k = m.curves[0];
  const int go = h.Send(SsWrite(Command::kMotionStart, stackshot::MotionStart{true, false, false}));
  const SsRecord* started = h.Await(go);
  ExpectOk(c, "SS-CURVE-005", started);
  if (started == nullptr) return;
  const TimeNs go_lo = h.requests()[static_cast<size_t>(go)].sent_ns, go_hi = started->t_ns;
  const TimeNs length = static_cast<TimeNs>(t_s * 1000) * kMs;
  size_t on_curve = 0;
  bool bad = false, moving_checked = false;
  while (h.Now() < go_hi + length && !h.link_lost()) {
    h.Idle(kCurveSampleNs);
    const int i =
        h.Send(SsRead(Command::kRailPositionCurrent, stackshot::UnitsQuery{Units::kMm}, 0));
    const SsRecord* r = h.Await(i);
    const auto* v = PayloadOf<stackshot::UnitsF32>(r);
    if (v == nullptr) continue;
    const double lo_s =
        static_cast<double>(h.requests()[static_cast<size_t>(i)].sent_ns - go_hi) / 1e9;
    const double hi_s = static_cast<double>(r->t_ns - go_lo) / 1e9;
    if (lo_s >= t_s) continue;
    ++on_curve;
    const double want_lo = CurveAt(k, lo_s) - 0.05, want_hi = CurveAt(k, hi_s) + 0.05;
    const double got = v->value.value();
    if (!bad && (got < want_lo || got > want_hi)) {
      bad = true;
      char expected[160];
      std::snprintf(expected, sizeof expected,
                    "on the curve %.3f-%.3f s after CC_MOTION_START: %.3f-%.3f mm", lo_s, hi_s,
                    want_lo, want_hi);
      c.v.Check("SS-CURVE-005", false,
                [&] { return EvOf(h, r, expected, stackshot::FormatF32(v->value) + " mm"); });
    }
    if (!moving_checked && hi_s >= kCurveMovingMarginS && hi_s < t_s - kCurveMovingMarginS) {
      moving_checked = true;
      const auto st = SsRailStatus(h, 0);
      Expect(c, "SS-CURVE-005", st && (*st & stackshot::kRailStatusMoving) != 0,
             "MOVING while the curve plays", st ? std::to_string(*st) : "no status");
    }
  }
  if (!bad) {
    Expect(c, "SS-CURVE-005", on_curve >= 3,
           "at least 3 positions read while the " + stackshot::FormatF32(static_cast<float>(t_s)) +
               " s curve plays",
           std::to_string(on_curve));
  }
  SsWaitRest(h, {0}, kRestWaitNs);
  const auto y = PositionMm(h, 0);
  const float last = k.p[3].y.value();
  Expect(c, "SS-CURVE-005", y && std::fabs(*y - last) <= 0.01f,
         "at rest on " + stackshot::FormatF32(last) + " mm (the last keyframe)", Mm(y));
}

void CurveCase(SsCaseContext& c) {
  SsHost& h = c.host;
  SsWaitRest(h, {0}, kRestWaitNs);
  const auto p0 = SsPositionSteps(h, 0);
  const auto y0 = PositionMm(h, 0);
  if (!p0 || !y0) return;
  const stackshot::MotionConfig one = Curve(*y0, 1.0f, 2.0f);
  ExpectOk(c, "SS-CURVE-001", h.Call(SsWrite(Command::kMotionConfig, one, 0)));
  PlayAlongTheCurve(c, one, 2.0);
  // Two curves in a row (five keyframes need not all be used).
  stackshot::MotionConfig two = Curve(*y0 + 1.0f, -0.5f, 1.0f);
  two.curves[1].p = {
      stackshot::BezierPoint{1.0f, *y0 + 0.5f}, {1.2f, *y0 + 0.5f}, {1.8f, *y0}, {2.0f, *y0}};
  ExpectOk(c, "SS-CURVE-001", h.Call(SsWrite(Command::kMotionConfig, two, 0)));
  // Requirements the list does not make: position continuity (only P0.x =
  // previous P3.x is required) and a speed within the axis ("Limits should be
  // applied": advice, no refusal). Accepted is taken: each is played and X
  // rests on its own last keyframe (a controller that acknowledged it and
  // kept the spline before would rest elsewhere).
  stackshot::MotionConfig jump = two;
  for (stackshot::BezierPoint& q : jump.curves[1].p) q.y = q.y.value() - 0.25f;
  ExpectOk(c, "SS-CURVE-001", h.Call(SsWrite(Command::kMotionConfig, jump, 0)));
  auto y = PlayX(c, "SS-CURVE-001");
  Expect(c, "SS-CURVE-001", y && std::fabs(*y - (*y0 - 0.25f)) <= 0.01f,
         "the curve with a position jump played: at rest on " + stackshot::FormatF32(*y0 - 0.25f) +
             " mm",
         Mm(y));
  // 2 mm in 10 ms outruns any rail.
  ExpectOk(c, "SS-CURVE-001", h.Call(SsWrite(Command::kMotionConfig, Curve(*y0, 2.0f, 0.01f), 0)));
  y = PlayX(c, "SS-CURVE-001");
  Expect(c, "SS-CURVE-001", y && std::fabs(*y - (*y0 + 2.0f)) <= 0.01f,
         "the curve faster than the axis played: at rest on " + stackshot::FormatF32(*y0 + 2.0f) +
             " mm",
         Mm(y));
  ReturnTo(c, 0, *p0);
}

void BadCurveCase(SsCaseContext& c) {
  SsHost& h = c.host;
  const float y = PositionMm(h, 0).value_or(0.0f);
  stackshot::MotionConfig m = Curve(y, 1.0f, 2.0f);
  m.curves[0].p[0].x = 0.5f;
  ExpectStatus(c, "SS-CURVE-002", h.Call(SsWrite(Command::kMotionConfig, m, 0)), Action::kBadParam);
  m = Curve(y, 1.0f, 2.0f);
  m.curves[1].p = {stackshot::BezierPoint{2.5f, y + 1.0f}, {2.7f, y + 1.0f}, {2.9f, y}, {3.0f, y}};
  ExpectStatus(c, "SS-CURVE-003", h.Call(SsWrite(Command::kMotionConfig, m, 0)), Action::kBadParam);
  m = Curve(y, 1.0f, 2.0f);
  m.curves[1].p = {stackshot::BezierPoint{2.0f, y + 1.0f}, {1.5f, y + 1.0f}, {2.5f, y}, {3.0f, y}};
  ExpectStatus(c, "SS-CURVE-004", h.Call(SsWrite(Command::kMotionConfig, m, 0)), Action::kBadParam);
  m = Curve(y, 1.0f, 2.0f);
  m.curves[0].p[2].x = 2.5f;
  ExpectStatus(c, "SS-CURVE-004", h.Call(SsWrite(Command::kMotionConfig, m, 0)), Action::kBadParam);
}

}  // namespace moco::conformance::ss_cases
