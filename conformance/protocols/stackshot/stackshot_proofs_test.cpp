// Proving tests of the StackShot 3X rules (stackshot-protocol.txt section 2
// and 1.1, 1.2 comm_action_t; ERRATA stackshot 1-6, 10; FACTS "StackShot"):
// the real emulated controller with one fault planted on the wire (its reply
// packets rewritten, dropped, repeated or delayed, or the host's packets
// changed before it reads them) fails the rule that names the fault, and few
// others.
#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "conformance/core/report.h"
#include "conformance/core/rule_proof_testing.h"
#include "conformance/protocols/stackshot/stackshot_broken_device_testing.h"
#include "conformance/protocols/stackshot/stackshot_protocol.h"
#include "conformance/rules/catalogue.h"

namespace moco::conformance {
namespace {

using proof::ExpectMustsFailed;
using proof::FailedMusts;

using namespace ss_testing;  // NOLINT: BrokenStackshot3x, RunBroken, Emit, PassThrough
using stackshot::Units;

constexpr sim::TimeNs kMs = sim::kNsPerMs;

// ------------------------------------------------------------------ support

RunOptions Only(const std::string& cases) {
  RunOptions o;
  o.cases = cases;
  return o;
}

// Replies answering `c` changed by `f`; every other packet as written.
Breakage OnReplyTo(Command c, std::function<void(const Packet& request, Packet& reply)> f) {
  return [c, f](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
    if (Is(request, c)) f(*request, reply);
    Emit(out, std::move(reply));
  };
}

// Host packets for `c` changed by `f` (nullopt: acknowledged, not acted on).
RequestBreakage OnRequest(Command c,
                          std::function<std::optional<Packet>(const Packet& request)> f) {
  return [c, f](const Packet& request) -> std::optional<Packet> {
    if (Is(&request, c)) return f(request);
    return request;
  };
}

// The typed payload T of a read reply changed by `f`.
template <typename T>
void EditReply(Packet& reply, const std::function<void(T&)>& f) {
  stackshot::ReplyContext context;
  context.request_action = Action::kRead;
  auto typed = stackshot::DecodeDevicePacket(reply, context);
  if (!typed) return;
  stackshot::DeviceReply r = std::move(typed).value();
  T* v = std::get_if<T>(&r.payload);
  if (v == nullptr) return;
  f(*v);
  reply = stackshot::ToPacket(r);
}

// The typed payload T of a host request changed by `f`.
template <typename T>
Packet EditRequest(const Packet& request, const std::function<void(T&)>& f) {
  auto typed = Typed(&request);
  if (!typed) return request;
  T* v = std::get_if<T>(&typed->payload);
  if (v == nullptr) return request;
  f(*v);
  return stackshot::ToPacket(*typed);
}

// The ping of 0xFF only connect/ping sends (discovery and greetings ping 0x5A).
bool IsPingOfFF(const Packet* request) {
  return Is(request, Command::kPing) && !request->data.empty() && request->data[0] == 0xff;
}

// ------------------------------------------------------------------ the filter

TEST(StackshotProofs, TheFilterWithNothingBrokenPassesTheWholeRun) {
  // Each packet the controller writes passes through as written and each
  // host packet is read as sent (re-encoded): no rule fails, so a rule that
  // fails below fails for the fault planted.
  const RunReport passed = RunBroken(PassThrough);
  EXPECT_EQ(ExitCode(passed), 0) << ConsoleReport(passed, false);
  EXPECT_TRUE(FailedMusts(passed).empty());
  const RunReport read =
      RunBroken(PassThrough, {}, [](const Packet& p) { return std::optional<Packet>(p); });
  EXPECT_EQ(ExitCode(read), 0) << ConsoleReport(read, false);
}

// ------------------------------------------------------------------ SS-PKT

TEST(StackshotProofs, AStrayByteBeforeAReplyIsCaughtByPkt001) {
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (IsPingOfFF(request)) {
          const uint8_t stray[] = {0x00};
          out.Write(stray);
        }
        Emit(out, std::move(reply));
      },
      Only("connect/ping"));
  ExpectCaught(r, "SS-PKT-001");
  ExpectMustsFailed(r, {"SS-PKT-001"});
}

TEST(StackshotProofs, AReplyCutShortIsCaughtByPkt002) {
  // The answer to the last request of connect/ping (a ping at 0x110A) stops
  // before its checksum byte.
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (request == nullptr || request->command != stackshot::kPingTableId) {
          Emit(out, std::move(reply));
          return;
        }
        Seal(reply, stackshot::ChecksumAlgorithm::kNegatedSum);
        wire::Bytes bytes;
        stackshot::EncodePacket(reply, bytes);
        bytes.pop_back();
        out.Write(bytes);
      },
      Only("connect/ping"));
  ExpectCaught(r, "SS-PKT-002");
  // A reply never finished leaves its request unanswered.
  ExpectMustsFailed(r, {"SS-PKT-002", "SS-ANS-001"});
}

TEST(StackshotProofs, AStatusOutsideTheResponseCodesIsCaughtByPkt003) {
  // The reply to a ping of 0xFF carries status 9 (COMM_ACTION_MAX), no response code.
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (IsPingOfFF(request)) reply.action = stackshot::kActionMax;
        Emit(out, std::move(reply));
      },
      Only("connect/ping"));
  ExpectCaught(r, "SS-PKT-003");
  // Not RSP_OK: the pings the case expects answered fail too.
  ExpectMustsFailed(r, {"SS-PKT-003", "SS-PING-001", "SS-CODE-003"});
}

TEST(StackshotProofs, AReplyWithoutTheRequestsAxisBitsIsCaughtByPkt004) {
  const RunReport r = RunBroken(
      [](const Packet*, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        reply.axis = 0;
        Emit(out, std::move(reply));
      },
      Only("errors/axis-3"));
  ExpectCaught(r, "SS-PKT-004");
  ExpectMustsFailed(r, {});
}

TEST(StackshotProofs, ARequestReadOnlyWhenItArrivesInOneReadIsCaughtByPkt005) {
  // A controller that drops what arrives a byte at a time.
  const RunReport r = RunBroken(
      PassThrough, Only("connect/bytewise"), {}, [](wire::ByteView bytes, sim::Scheduler&) {
        return bytes.size() == 1 ? wire::Bytes{} : wire::Bytes(bytes.begin(), bytes.end());
      });
  ExpectCaught(r, "SS-PKT-005");
  // The ping the case expects answered RSP_OK goes unanswered.
  ExpectMustsFailed(r, {"SS-PKT-005", "SS-ANS-001", "SS-CODE-003"});
}

TEST(StackshotProofs, APartialPacketKeptAcrossTheGapIsCaughtByPkt006) {
  // A controller without the 2 ms re-sync: a partial packet swallows the
  // bytes of the next request as its data.
  auto glued = std::make_shared<stackshot::PacketDecoder>(/*from_device=*/false);
  const RunReport r = RunBroken(PassThrough, Only("connect/resync"), {},
                                [glued](wire::ByteView bytes, sim::Scheduler&) {
                                  std::vector<stackshot::DecodedPacket> packets;
                                  glued->Feed(bytes, packets);
                                  wire::Bytes whole;
                                  for (const auto& d : packets)
                                    stackshot::EncodePacket(d.packet, whole);
                                  return whole;
                                });
  ExpectCaught(r, "SS-PKT-006");
  ExpectMustsFailed(r, {"SS-PKT-006", "SS-ANS-001"});
}

// ------------------------------------------------------------------ SS-CSUM

TEST(StackshotProofs, ARequestRefusedForItsChecksumByteIsCaughtByCsum003) {
  // Requests whose checksum is not the negated sum are refused BAD_PARAM.
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (request != nullptr &&
            !stackshot::ChecksumMatches(*request, stackshot::ChecksumAlgorithm::kNegatedSum)) {
          reply = WithStatus(std::move(reply), Action::kBadParam);
        }
        Emit(out, std::move(reply));
      },
      Only("connect/checksums"));
  ExpectCaught(r, "SS-CSUM-003");
  ExpectMustsFailed(r, {"SS-CSUM-003", "SS-CODE-003"});
}

// ------------------------------------------------------------------ SS-ANS

TEST(StackshotProofs, APingAnsweredTwiceIsCaughtByAns002) {
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (IsPingOfFF(request)) Emit(out, reply);
        Emit(out, std::move(reply));
      },
      Only("connect/ping"));
  ExpectCaught(r, "SS-ANS-002");
  ExpectMustsFailed(r, {"SS-ANS-002"});
}

// ------------------------------------------------------------------ SS-CODE

TEST(StackshotProofs, AKnownReadAnsweredUnsupportedCmdIsCaughtByCode001) {
  const RunReport r = RunBroken(OnReplyTo(Command::kSoftwareId,
                                          [](const Packet&, Packet& reply) {
                                            reply = WithStatus(reply, Action::kUnsupportedCmd);
                                          }),
                                Only("connect/identity"));
  ExpectCaught(r, "SS-CODE-001");
  // connect/identity expects the id read RSP_OK with its layout.
  ExpectMustsFailed(r, {"SS-CODE-001", "SS-CODE-003", "SS-LAYOUT-001"});
}

TEST(StackshotProofs, AReadAnsweredBusyIsCaughtByCode002) {
  const RunReport r = RunBroken(
      OnReplyTo(Command::kHardwareId,
                [](const Packet&, Packet& reply) { reply = WithStatus(reply, Action::kBusy); }),
      Only("connect/identity"));
  ExpectCaught(r, "SS-CODE-002");
  ExpectMustsFailed(r, {"SS-CODE-003", "SS-LAYOUT-001"});
}

// ------------------------------------------------------------------ SS-LAYOUT

TEST(StackshotProofs, AReadReplyLongerThanItsLayoutIsCaughtByLayout001) {
  // CC_SOFTWARE_ID answers 5 bytes instead of its u32.
  const RunReport r =
      RunBroken(OnReplyTo(Command::kSoftwareId,
                          [](const Packet&, Packet& reply) { reply.data.push_back(0); }),
                Only("connect/identity"));
  ExpectCaught(r, "SS-LAYOUT-001");
  ExpectMustsFailed(r, {"SS-LAYOUT-001"});
}

TEST(StackshotProofs, AWriteAcknowledgementWithDataIsCaughtByLayout002) {
  const RunReport r = RunBroken(OnReplyTo(Command::kRailPositionZero,
                                          [](const Packet&, Packet& reply) {
                                            if (!Refused(reply)) reply.data.push_back(0);
                                          }),
                                Only("rail/zero"));
  ExpectCaught(r, "SS-LAYOUT-002");
  ExpectMustsFailed(r, {"SS-LAYOUT-002"});
}

TEST(StackshotProofs, AnErrorReplyWithDataIsCaughtByLayout003) {
  const RunReport r = RunBroken(
      [](const Packet*, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (Refused(reply)) reply.data.push_back(0x03);
        Emit(out, std::move(reply));
      },
      Only("errors/axis-3"));
  ExpectCaught(r, "SS-LAYOUT-003");
  ExpectMustsFailed(r, {});
}

TEST(StackshotProofs, APositionInOtherUnitsThanAskedIsCaughtByLayout004) {
  // A position asked in mm is answered labelled mils (the value unchanged).
  const RunReport r =
      RunBroken(OnReplyTo(Command::kRailPositionCurrent,
                          [](const Packet& request, Packet& reply) {
                            if (!request.data.empty() &&
                                request.data[0] == static_cast<uint8_t>(Units::kMm) &&
                                !reply.data.empty() && !Refused(reply)) {
                              reply.data[0] = static_cast<uint8_t>(Units::kMils);
                            }
                          }),
                Only("rail/at-rest"));
  ExpectCaught(r, "SS-LAYOUT-004");
  ExpectMustsFailed(r, {"SS-LAYOUT-004"});
}

// ------------------------------------------------------------------ SS-ERR

TEST(StackshotProofs, AnUnknownCommandAnsweredBadParamIsCaughtByErr001) {
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (request != nullptr && stackshot::FindCommand(request->command) == nullptr) {
          reply = WithStatus(std::move(reply), Action::kBadParam);
        }
        Emit(out, std::move(reply));
      },
      Only("errors/unknown-command"));
  ExpectCaught(r, "SS-ERR-001");
  ExpectMustsFailed(r, {"SS-ERR-001"});
}

TEST(StackshotProofs, AForbiddenActionAnsweredBadParamIsCaughtByErr002) {
  const RunReport r = RunBroken(
      [](const Packet*, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (reply.action == static_cast<uint8_t>(Action::kUnsupportedAction)) {
          reply = WithStatus(std::move(reply), Action::kBadParam);
        }
        Emit(out, std::move(reply));
      },
      Only("errors/bad-action"));
  ExpectCaught(r, "SS-ERR-002");
  ExpectMustsFailed(r, {"SS-ERR-002"});
}

TEST(StackshotProofs, AShortMoveAcceptedIsCaughtByErr003) {
  // A CC_RAIL_MOVE of 3 data bytes (7 expected) is answered RSP_OK.
  const RunReport r = RunBroken(OnReplyTo(Command::kRailMove,
                                          [](const Packet& request, Packet& reply) {
                                            if (request.data.size() == 3) {
                                              reply = WithStatus(reply, Action::kRspOk);
                                            }
                                          }),
                                Only("errors/bad-length"));
  ExpectCaught(r, "SS-ERR-003");
  ExpectMustsFailed(r, {"SS-ERR-003"});
}

TEST(StackshotProofs, AxisThreeRefusedOtherThanBadParamIsCaughtByErr005) {
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (request != nullptr && request->axis == 3) {
          reply = WithStatus(std::move(reply), Action::kFailed);
        }
        Emit(out, std::move(reply));
      },
      Only("errors/axis-3"));
  ExpectCaught(r, "SS-ERR-005");
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ SS-PING

TEST(StackshotProofs, APingEchoedWithoutTheXorIsCaughtByPing001) {
  const RunReport r = RunBroken(OnReplyTo(Command::kPing,
                                          [](const Packet& request, Packet& reply) {
                                            if (!request.data.empty() && !reply.data.empty()) {
                                              reply.data[0] = request.data[0];
                                            }
                                          }),
                                Only("connect/ping"));
  ExpectCaught(r, "SS-PING-001");
  ExpectMustsFailed(r, {"SS-PING-001"});
}

// ------------------------------------------------------------------ SS-ID

TEST(StackshotProofs, ASoftwareStringWithoutItsNulIsCaughtById001) {
  const RunReport r = RunBroken(OnReplyTo(Command::kSoftwareString,
                                          [](const Packet&, Packet& reply) {
                                            if (!reply.data.empty() && reply.data.back() == 0) {
                                              reply.data.pop_back();
                                            }
                                          }),
                                Only("connect/identity"));
  ExpectCaught(r, "SS-ID-001");
  ExpectMustsFailed(r, {"SS-ID-001"});
}

TEST(StackshotProofs, AHardwareIdThatChangesIsCaughtById002) {
  // Each read of CC_HARDWARE_ID answers one more than the read before.
  auto reads = std::make_shared<uint32_t>(0);
  const RunReport r = RunBroken(OnReplyTo(Command::kHardwareId,
                                          [reads](const Packet&, Packet& reply) {
                                            const uint32_t more = ++*reads;
                                            EditReply<stackshot::U32Value>(
                                                reply, [more](auto& v) { v.value += more; });
                                          }),
                                Only("connect/identity"));
  ExpectCaught(r, "SS-ID-002");
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ SS-SERIAL

// Once `trigger` has been acknowledged, reads of `c` answer `value`.
Breakage AfterAnAck(Command trigger, Command c, std::function<void(const Packet&, Packet&)> f) {
  auto seen = std::make_shared<bool>(false);
  return [trigger, c, f, seen](const Packet* request, Packet reply, sim::Scheduler&,
                               devices::ByteSink& out) {
    if (Is(request, trigger) && !Refused(reply)) *seen = true;
    if (*seen && Is(request, c) && request->action == static_cast<uint8_t>(Action::kRead) &&
        !Refused(reply)) {
      f(*request, reply);
    }
    Emit(out, std::move(reply));
  };
}

void Unprogrammed(const Packet&, Packet& reply) {
  EditReply<stackshot::U32Value>(reply, [](auto& v) { v.value = stackshot::kUnprogrammed; });
}

TEST(StackshotProofs, ASerialNumberLostOnResetIsCaughtBySerial003) {
  // nvm/serial burns the number that nvm/persist then reads across CC_RESET.
  const RunReport r =
      RunBroken(AfterAnAck(Command::kReset, Command::kSerialNumber, Unprogrammed), Only("nvm/*"));
  ExpectCaught(r, "SS-SERIAL-003");
  ExpectMustsFailed(r, {"SS-SERIAL-003"});
}

TEST(StackshotProofs, AFirstSerialNumberNotStoredIsCaughtBySerial004) {
  // The first write is acknowledged, yet the number reads unprogrammed.
  const RunReport r = RunBroken(
      AfterAnAck(Command::kSerialNumber, Command::kSerialNumber, Unprogrammed), Only("nvm/serial"));
  ExpectCaught(r, "SS-SERIAL-004");
  ExpectMustsFailed(r, {"SS-SERIAL-004"});
}

// ------------------------------------------------------------------ SS-NVM

// The NVM register a CC_NVM_ACCESS request names.
std::optional<uint8_t> Register(const Packet& request) {
  if (request.data.empty()) return std::nullopt;
  return request.data[0];
}

TEST(StackshotProofs, AnNvmRegisterReadingOtherThanWrittenIsCaughtByNvm001) {
  // Registers 1-127 read back with their lowest bit flipped.
  const RunReport r = RunBroken(
      OnReplyTo(Command::kNvmAccess,
                [](const Packet& request, Packet& reply) {
                  const auto reg = Register(request);
                  if (request.action == static_cast<uint8_t>(Action::kRead) && reg && *reg != 0) {
                    EditReply<stackshot::U32Value>(reply, [](auto& v) { v.value ^= 1u; });
                  }
                }),
      Only("nvm/registers"));
  ExpectCaught(r, "SS-NVM-001");
  ExpectMustsFailed(r, {"SS-NVM-001"});
}

TEST(StackshotProofs, AnNvmRegisterBeyondTheRangeAcceptedIsCaughtByNvm002) {
  const RunReport r =
      RunBroken(OnReplyTo(Command::kNvmAccess,
                          [](const Packet& request, Packet& reply) {
                            const auto reg = Register(request);
                            if (!reg || *reg < stackshot::kNvmRegisterCountSerial) return;
                            reply = WithStatus(reply, Action::kRspOk);
                            if (request.action == static_cast<uint8_t>(Action::kRead)) {
                              reply.data.assign(4, 0x00);
                            }
                          }),
                Only("nvm/registers"));
  ExpectCaught(r, "SS-NVM-002");
  ExpectMustsFailed(r, {"SS-NVM-002"});
}

TEST(StackshotProofs, AnNvmRegisterLostOnResetIsCaughtByNvm003) {
  const RunReport r = RunBroken(AfterAnAck(Command::kReset, Command::kNvmAccess, Unprogrammed),
                                Only("nvm/persist"));
  ExpectCaught(r, "SS-NVM-003");
  ExpectMustsFailed(r, {"SS-NVM-003"});
}

TEST(StackshotProofs, AnNvmRegisterZeroApartFromTheAxisIsCaughtByNvm004) {
  // Register 0 always reads 0, whatever CC_RAIL_CONFIG_AXIS holds.
  const RunReport r =
      RunBroken(OnReplyTo(Command::kNvmAccess,
                          [](const Packet& request, Packet& reply) {
                            if (request.action == static_cast<uint8_t>(Action::kRead) &&
                                Register(request) == 0) {
                              EditReply<stackshot::U32Value>(reply, [](auto& v) { v.value = 0; });
                            }
                          }),
                Only("nvm/registers"));
  ExpectCaught(r, "SS-NVM-004");
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ SS-STATUS

// Every CC_RAIL_STATUS reply's bits changed by `f`.
Breakage StatusBits(std::function<uint32_t(uint32_t)> f) {
  return OnReplyTo(Command::kRailStatus, [f](const Packet&, Packet& reply) {
    EditReply<stackshot::RailStatus>(reply, [f](auto& s) { s.bits = f(s.bits); });
  });
}

TEST(StackshotProofs, AnUndocumentedStatusBitIsCaughtByStatus001) {
  const RunReport r =
      RunBroken(StatusBits([](uint32_t b) { return b | 0x10u; }), Only("rail/at-rest"));
  ExpectCaught(r, "SS-STATUS-001");
  ExpectMustsFailed(r, {"SS-STATUS-001"});
}

TEST(StackshotProofs, MovingReportedAtRestIsCaughtByStatus003) {
  const RunReport r =
      RunBroken(StatusBits([](uint32_t b) { return b | stackshot::kRailStatusMoving; }),
                Only("rail/at-rest"));
  ExpectCaught(r, "SS-STATUS-003");
  ExpectMustsFailed(r, {"SS-STATUS-003"});
}

TEST(StackshotProofs, AShutterBitNeverSetIsCaughtByStatus004) {
  const RunReport r =
      RunBroken(StatusBits([](uint32_t b) { return b & ~stackshot::kRailStatusShutter; }),
                Only("rail/shutter"));
  ExpectCaught(r, "SS-STATUS-004");
  // The host, told the pulses are over, fires again while they still run:
  // that fire is refused BUSY.
  ExpectMustsFailed(r, {"SS-STATUS-004", "SS-SHUT-001", "SS-CODE-003"});
}

TEST(StackshotProofs, UserAbortedWithoutAnAbortIsCaughtByStatus005) {
  const RunReport r =
      RunBroken(StatusBits([](uint32_t b) { return b | stackshot::kRailStatusUserAborted; }),
                Only("rail/user-abort"));
  ExpectCaught(r, "SS-STATUS-005");
  ExpectMustsFailed(r, {"SS-STATUS-005"});
}

// ------------------------------------------------------------------ SS-POS

// A CC_RAIL_MOVE of `steps` forward on the axis of `request`, read in its place.
Packet MoveInstead(const Packet& request, float steps) {
  stackshot::RailMove m;
  m.direction = stackshot::Direction::kForward;
  m.units = Units::kSteps;
  m.distance = steps;
  stackshot::HostCommand c;
  c.command = stackshot::Id(Command::kRailMove);
  c.action = Action::kWrite;
  c.axis = request.axis;
  c.payload = m;
  return stackshot::ToPacket(c);
}

TEST(StackshotProofs, AZeroThatMovesTheRailIsCaughtByPos001) {
  // CC_RAIL_POSITION_ZERO is carried out as a 100-step move.
  const RunReport r = RunBroken(PassThrough, Only("rail/zero"),
                                OnRequest(Command::kRailPositionZero, [](const Packet& p) {
                                  return std::optional<Packet>(MoveInstead(p, 100.0f));
                                }));
  ExpectCaught(r, "SS-POS-001");
  ExpectMustsFailed(r, {"SS-POS-001"});
}

TEST(StackshotProofs, AZeroAcceptedWhileMovingIsCaughtByPos002) {
  const RunReport r =
      RunBroken(OnReplyTo(Command::kRailPositionZero,
                          [](const Packet&, Packet& reply) {
                            if (reply.action == static_cast<uint8_t>(Action::kBusy)) {
                              reply = WithStatus(reply, Action::kRspOk);
                            }
                          }),
                Only("rail/move"));
  ExpectCaught(r, "SS-POS-002");
  ExpectMustsFailed(r, {"SS-POS-002"});
}

TEST(StackshotProofs, MillimetresOffByATenthIsCaughtByPos003) {
  // Positions read in mm are 0.1 mm more than the same position in mils says.
  const RunReport r = RunBroken(OnReplyTo(Command::kRailPositionCurrent,
                                          [](const Packet&, Packet& reply) {
                                            EditReply<stackshot::UnitsF32>(reply, [](auto& v) {
                                              if (v.units == Units::kMm)
                                                v.value = v.value.value() + 0.1f;
                                            });
                                          }),
                                Only("rail/at-rest"));
  ExpectCaught(r, "SS-POS-003");
  ExpectMustsFailed(r, {"SS-POS-003"});
}

TEST(StackshotProofs, ATargetAStepAwayAtRestIsCaughtByPos004) {
  const RunReport r = RunBroken(OnReplyTo(Command::kRailPositionTarget,
                                          [](const Packet&, Packet& reply) {
                                            EditReply<stackshot::UnitsF32>(reply, [](auto& v) {
                                              v.value = v.value.value() + 1.0f;
                                            });
                                          }),
                                Only("rail/at-rest"));
  ExpectCaught(r, "SS-POS-004");
  ExpectMustsFailed(r, {"SS-POS-004"});
}

// ------------------------------------------------------------------ SS-MOVE

// Halves the distance of a move request (CC_RAIL_MOVE or _AT_SPEED).
template <typename M>
std::optional<Packet> HalfTheDistance(const Packet& request) {
  return EditRequest<M>(request, [](M& m) { m.distance = m.distance.value() / 2; });
}

TEST(StackshotProofs, AMoveOfHalfTheDistanceIsCaughtByMove001) {
  const RunReport r =
      RunBroken(PassThrough, Only("rail/move"),
                OnRequest(Command::kRailMove, HalfTheDistance<stackshot::RailMove>));
  ExpectCaught(r, "SS-MOVE-001");
  // The refused move's check compares with the full distance too.
  ExpectMustsFailed(r, {"SS-MOVE-001", "SS-MOVE-002"});
}

TEST(StackshotProofs, AMoveAcceptedWhileMovingIsCaughtByMove002) {
  // The BUSY refusal is answered RSP_OK (the move under way goes on).
  const RunReport r =
      RunBroken(OnReplyTo(Command::kRailMove,
                          [](const Packet&, Packet& reply) {
                            if (reply.action == static_cast<uint8_t>(Action::kBusy)) {
                              reply = WithStatus(reply, Action::kRspOk);
                            }
                          }),
                Only("rail/move"));
  ExpectCaught(r, "SS-MOVE-002");
  ExpectMustsFailed(r, {"SS-MOVE-002"});
}

TEST(StackshotProofs, AMoveAtSpeedOfHalfTheDistanceIsCaughtByMove003) {
  const RunReport r =
      RunBroken(PassThrough, Only("rail/move-at-speed"),
                OnRequest(Command::kRailMoveAtSpeed, HalfTheDistance<stackshot::RailMoveAtSpeed>));
  ExpectCaught(r, "SS-MOVE-003");
  ExpectMustsFailed(r, {"SS-MOVE-003"});
}

// Whether the rail is under way as the replies tell: a CC_RAIL_MOVE accepted
// sets it, a CC_RAIL_STATUS without MOVING clears it.
struct Motion {
  bool moving = false;
  void See(const Packet* request, const Packet& reply) {
    if (Is(request, Command::kRailMove) && !Refused(reply)) moving = true;
    if (Is(request, Command::kRailStatus) && !Refused(reply)) {
      stackshot::ReplyContext context;
      context.request_action = Action::kRead;
      auto typed = stackshot::DecodeDevicePacket(reply, context);
      if (typed) {
        if (const auto* s = std::get_if<stackshot::RailStatus>(&typed.value().payload)) {
          moving = (s->bits & stackshot::kRailStatusMoving) != 0;
        }
      }
    }
  }
};

TEST(StackshotProofs, AMoveAtSpeedRefusedBusyWhileMovingIsCaughtByMove004) {
  auto motion = std::make_shared<Motion>();
  const RunReport r = RunBroken(
      [motion](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (Is(request, Command::kRailMoveAtSpeed) && motion->moving) {
          reply = WithStatus(std::move(reply), Action::kBusy);
        }
        motion->See(request, reply);
        Emit(out, std::move(reply));
      },
      Only("rail/move-at-speed"));
  ExpectCaught(r, "SS-MOVE-004");
  ExpectMustsFailed(r, {});
}

TEST(StackshotProofs, ABadMoveAcceptedIsCaughtByMove005) {
  // Refusals of moves are answered RSP_OK (the rail stays).
  const RunReport r = RunBroken(
      [](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if ((Is(request, Command::kRailMove) || Is(request, Command::kRailMoveAtSpeed)) &&
            reply.action == static_cast<uint8_t>(Action::kBadParam)) {
          reply = WithStatus(std::move(reply), Action::kRspOk);
        }
        Emit(out, std::move(reply));
      },
      Only("rail/bad-move"));
  ExpectCaught(r, "SS-MOVE-005");
  ExpectMustsFailed(r, {"SS-MOVE-005"});
}

// ------------------------------------------------------------------ SS-STOP

TEST(StackshotProofs, AStopAcknowledgedButIgnoredIsCaughtByStop001) {
  const RunReport r = RunBroken(
      PassThrough, Only("rail/stop"),
      OnRequest(Command::kRailStop, [](const Packet&) { return std::optional<Packet>(); }));
  ExpectCaught(r, "SS-STOP-001");
  // The STOP "at rest" then meets a rail still under way, which goes on.
  ExpectMustsFailed(r, {"SS-STOP-001", "SS-STOP-002"});
}

TEST(StackshotProofs, AStopAtRestThatMovesIsCaughtByStop002) {
  // At rest, CC_RAIL_STOP is carried out as a 100-step move.
  auto motion = std::make_shared<Motion>();
  const RunReport r = RunBroken(
      [motion](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        motion->See(request, reply);
        Emit(out, std::move(reply));
      },
      Only("rail/stop"),
      [motion](const Packet& request) -> std::optional<Packet> {
        if (Is(&request, Command::kRailStop) && !motion->moving) {
          return MoveInstead(request, 100.0f);
        }
        return request;
      });
  ExpectCaught(r, "SS-STOP-002");
  ExpectMustsFailed(r, {"SS-STOP-002"});
}

// ------------------------------------------------------------------ SS-SHUT

TEST(StackshotProofs, AnOutOfRangeShutterFireRefusedIsCaughtByShut001) {
  // A fire of 0 pulses or a negative time is refused, not bounded.
  const RunReport r = RunBroken(
      OnReplyTo(Command::kRailShutterFire,
                [](const Packet& request, Packet& reply) {
                  const auto typed = Typed(&request);
                  const auto* f =
                      typed ? std::get_if<stackshot::ShutterFire>(&typed->payload) : nullptr;
                  if (f != nullptr && (f->pulses == 0 || f->on_time_s.value() <= 0)) {
                    reply = WithStatus(reply, Action::kBadParam);
                  }
                }),
      Only("rail/shutter"));
  ExpectCaught(r, "SS-SHUT-001");
  ExpectMustsFailed(r, {"SS-SHUT-001", "SS-CODE-003"});
}

// ------------------------------------------------------------------ SS-CFG

// Refusals of writes to `c` answered RSP_OK.
Breakage RefusalsAccepted(Command c) {
  return OnReplyTo(c, [](const Packet& request, Packet& reply) {
    if (request.action == static_cast<uint8_t>(Action::kWrite) && Refused(reply)) {
      reply = WithStatus(reply, Action::kRspOk);
    }
  });
}

// Writes of `c` acknowledged without reaching the controller.
RequestBreakage WritesIgnored(Command c, std::function<bool(const Packet&)> which = {}) {
  return OnRequest(c, [which](const Packet& request) -> std::optional<Packet> {
    if (request.action != static_cast<uint8_t>(Action::kWrite)) return request;
    if (which && !which(request)) return request;
    return std::nullopt;
  });
}

TEST(StackshotProofs, ATorqueWriteThatDoesNotStickIsCaughtByCfg001) {
  const RunReport r =
      RunBroken(PassThrough, Only("config/values"), WritesIgnored(Command::kRailConfigTorque));
  ExpectCaught(r, "SS-CFG-001");
  ExpectMustsFailed(r, {"SS-CFG-001"});
}

TEST(StackshotProofs, ABacklightOutOfRangeAcceptedIsCaughtByCfg002) {
  const RunReport r =
      RunBroken(RefusalsAccepted(Command::kRailConfigBacklight), Only("config/ranges"));
  ExpectCaught(r, "SS-CFG-002");
  ExpectMustsFailed(r, {"SS-CFG-002"});
}

TEST(StackshotProofs, ASpeedInMilsThatIsReallyMillimetresIsCaughtByCfg003) {
  // CC_RAIL_CONFIG_SPEED asked in mils answers the mm figure.
  const RunReport r = RunBroken(OnReplyTo(Command::kRailConfigSpeed,
                                          [](const Packet&, Packet& reply) {
                                            EditReply<stackshot::UnitsF32>(reply, [](auto& v) {
                                              if (v.units == Units::kMils)
                                                v.value = v.value.value() * 0.0254f;
                                            });
                                          }),
                                Only("config/units"));
  ExpectCaught(r, "SS-CFG-003");
  ExpectMustsFailed(r, {"SS-CFG-003"});
}

TEST(StackshotProofs, ANegativeSettleTimeAcceptedIsCaughtByCfg004) {
  const RunReport r =
      RunBroken(RefusalsAccepted(Command::kRailConfigSettleTime), Only("config/ranges"));
  ExpectCaught(r, "SS-CFG-004");
  ExpectMustsFailed(r, {});
}

TEST(StackshotProofs, AConfigurationNameWithoutItsNulIsCaughtByCfg005) {
  const RunReport r =
      RunBroken(OnReplyTo(Command::kRailConfigName,
                          [](const Packet& request, Packet& reply) {
                            if (request.action == static_cast<uint8_t>(Action::kRead) &&
                                !reply.data.empty() && reply.data.back() == 0) {
                              reply.data.pop_back();
                            }
                          }),
                Only("config/name"));
  ExpectCaught(r, "SS-CFG-005");
  ExpectMustsFailed(r, {"SS-CFG-005"});
}

// ------------------------------------------------------------------ SS-SLOT

// The slot a CC_RAIL_CONFIG_SAVE/LOAD request names.
std::optional<uint8_t> Slot(const Packet& request) {
  if (request.data.empty()) return std::nullopt;
  return request.data[0];
}

TEST(StackshotProofs, ALoadThatRestoresNothingIsCaughtBySlot001) {
  const RunReport r = RunBroken(PassThrough, Only("config/slots"),
                                WritesIgnored(Command::kRailConfigLoad, [](const Packet& p) {
                                  const auto slot = Slot(p);
                                  return slot && *slot >= 1 && *slot <= stackshot::kConfigSlotMax;
                                }));
  ExpectCaught(r, "SS-SLOT-001");
  // The slot-7 LOAD that must be refused is acknowledged too.
  ExpectMustsFailed(r, {"SS-SLOT-001", "SS-SLOT-002"});
}

TEST(StackshotProofs, ALoadOfAnEmptySlotAcceptedIsCaughtBySlot002) {
  const RunReport r = RunBroken(RefusalsAccepted(Command::kRailConfigLoad), Only("config/slots"));
  ExpectCaught(r, "SS-SLOT-002");
  ExpectMustsFailed(r, {"SS-SLOT-002"});
}

TEST(StackshotProofs, ASaveToSlotZeroIgnoredIsCaughtBySlot003) {
  const RunReport r = RunBroken(
      PassThrough, Only("config/power-on"),
      WritesIgnored(Command::kRailConfigSave, [](const Packet& p) { return Slot(p) == 0; }));
  ExpectCaught(r, "SS-SLOT-003");
  ExpectMustsFailed(r, {"SS-SLOT-003"});
}

// ------------------------------------------------------------------ SS-RESET

TEST(StackshotProofs, AControllerSilentAfterResetIsCaughtByReset001) {
  // CC_RESET is acknowledged, then nothing more is ever answered.
  auto reset = std::make_shared<bool>(false);
  const RunReport r = RunBroken(
      [reset](const Packet* request, Packet reply, sim::Scheduler&, devices::ByteSink& out) {
        if (*reset) return;
        if (Is(request, Command::kReset)) *reset = true;
        Emit(out, std::move(reply));
      },
      Only("config/power-on"));
  ExpectCaught(r, "SS-RESET-001");
  ExpectMustsFailed(r, {"SS-RESET-001", "SS-ANS-001"});
}

TEST(StackshotProofs, AResetThatKeepsUnsavedSettingsIsCaughtByReset002) {
  // CC_RESET acknowledged without resetting anything.
  const RunReport r =
      RunBroken(PassThrough, Only("config/power-on"), WritesIgnored(Command::kReset));
  ExpectCaught(r, "SS-RESET-002");
  // Nor is slot 0's configuration loaded.
  ExpectMustsFailed(r, {"SS-SLOT-003"});
}

// ------------------------------------------------------------------ SS-DL

// Replies answering `c` written `delay_ns` late.
Breakage Late(Command c, sim::TimeNs delay_ns) {
  return [c, delay_ns](const Packet* request, Packet reply, sim::Scheduler& s,
                       devices::ByteSink& out) {
    if (!Is(request, c)) {
      Emit(out, std::move(reply));
      return;
    }
    s.After(delay_ns, [&out, reply] { Emit(out, reply); });
  };
}

TEST(StackshotProofs, AStatusAnsweredLateIsCaughtByDl001) {
  // 400 ms: past the 250 ms deadline, within the 2 s answer timeout.
  const RunReport r = RunBroken(Late(Command::kRailStatus, 400 * kMs), Only("rail/at-rest"));
  ExpectCaught(r, "SS-DL-001");
  ExpectMustsFailed(r, {});
}

TEST(StackshotProofs, AStopAcknowledgedLateIsCaughtByDl002) {
  const RunReport r = RunBroken(Late(Command::kRailStop, 400 * kMs), Only("rail/stop"));
  ExpectCaught(r, "SS-DL-002");
  ExpectMustsFailed(r, {});
}

TEST(StackshotProofs, ASoftwareChecksumAnsweredAfterASecondIsCaughtByDl003) {
  // 1 s on top of the controller's own 250 ms.
  const RunReport r =
      RunBroken(Late(Command::kSoftwareChecksum, 1000 * kMs), Only("connect/identity"));
  ExpectCaught(r, "SS-DL-003");
  ExpectMustsFailed(r, {});
}

// ------------------------------------------------------------------ SS-STACK

TEST(StackshotProofs, AStackThatCountsItsFramesWithoutMovingIsCaughtByStack001) {
  // CC_RAIL_STACK read with each axis's end at its start: the frames are
  // counted and shot where the rail stands.
  const RunReport r =
      RunBroken(PassThrough, Only("stack/run"), OnRequest(Command::kRailStack, [](const Packet& p) {
                  return std::optional<Packet>(EditRequest<stackshot::RailStack>(p, [](auto& s) {
                    s.x_end = s.x_start;
                    s.y_end = s.y_start;
                    s.z_end = s.z_start;
                  }));
                }));
  ExpectCaught(r, "SS-STACK-001");
  ExpectMustsFailed(r, {"SS-STACK-001"});
}

TEST(StackshotProofs, AStackThatCountsItsFramesWithoutFiringIsCaughtByStack001) {
  // The shutter the host names for the stack's axis is read as NONE: the
  // rail steps from start to end and counts its frames, no picture is taken.
  const RunReport r = RunBroken(
      PassThrough, Only("stack/run"), OnRequest(Command::kRailConfigShutter, [](const Packet& p) {
        if (p.action != static_cast<uint8_t>(Action::kWrite)) return std::optional<Packet>(p);
        return std::optional<Packet>(EditRequest<stackshot::EnumValue<stackshot::ShutterSetting>>(
            p, [](auto& v) { v.value = stackshot::ShutterSetting::kNone; }));
      }));
  ExpectCaught(r, "SS-STACK-001");
  ExpectMustsFailed(r, {"SS-STACK-001"});
}

TEST(StackshotProofs, AStackAcceptedWhileAnAxisMovesIsCaughtByStack002) {
  const RunReport r =
      RunBroken(OnReplyTo(Command::kRailStack,
                          [](const Packet&, Packet& reply) {
                            if (reply.action == static_cast<uint8_t>(Action::kBusy)) {
                              reply = WithStatus(reply, Action::kRspOk);
                            }
                          }),
                Only("stack/run"));
  ExpectCaught(r, "SS-STACK-002");
  ExpectMustsFailed(r, {"SS-STACK-002"});
}

// ------------------------------------------------------------------ SS-CURVE

// The CC_MOTION_CONFIG a host packet carries, or nullopt.
std::optional<stackshot::MotionConfig> MotionOf(const Packet& request) {
  const auto typed = Typed(&request);
  if (!typed) return std::nullopt;
  const auto* m = std::get_if<stackshot::MotionConfig>(&typed->payload);
  if (m == nullptr) return std::nullopt;
  return *m;
}

// A used curve (curve 0, or one whose P0.x is not zero) that starts elsewhere
// than the curve before it ends.
bool HasAPositionJump(const stackshot::MotionConfig& m) {
  for (size_t k = 1; k < m.curves.size(); ++k) {
    const auto& c = m.curves[k];
    if (c.p[0].x.value() == 0.0f) break;
    if (c.p[0].y.value() != m.curves[k - 1].p[3].y.value()) return true;
  }
  return false;
}

// CC_MOTION_CONFIG writes for which `when` holds answered `status`.
Breakage MotionConfigAnswered(std::function<bool(const stackshot::MotionConfig&)> when,
                              Action status) {
  return OnReplyTo(Command::kMotionConfig, [when, status](const Packet& request, Packet& reply) {
    const auto m = MotionOf(request);
    if (m && when(*m)) reply = WithStatus(reply, status);
  });
}

TEST(StackshotProofs, ASplineWithAPositionJumpRefusedIsCaughtByCurve001) {
  // A controller that requires position continuity, which the list does not.
  const RunReport r =
      RunBroken(MotionConfigAnswered(HasAPositionJump, Action::kBadParam), Only("curve/play"));
  ExpectCaught(r, "SS-CURVE-001");
  ExpectMustsFailed(r, {"SS-CURVE-001", "SS-CODE-003"});
}

TEST(StackshotProofs, ASplineAcknowledgedButNotTakenIsCaughtByCurve001) {
  // The spline with a position jump is acknowledged and dropped: the one
  // before it plays instead.
  const RunReport r = RunBroken(PassThrough, Only("curve/play"),
                                OnRequest(Command::kMotionConfig, [](const Packet& p) {
                                  const auto m = MotionOf(p);
                                  if (m && HasAPositionJump(*m)) return std::optional<Packet>();
                                  return std::optional<Packet>(p);
                                }));
  ExpectCaught(r, "SS-CURVE-001");
  ExpectMustsFailed(r, {"SS-CURVE-001"});
}

TEST(StackshotProofs, ACurveZeroNotStartingAtTimeZeroAcceptedIsCaughtByCurve002) {
  const RunReport r = RunBroken(
      MotionConfigAnswered(
          [](const stackshot::MotionConfig& m) { return m.curves[0].p[0].x.value() != 0.0f; },
          Action::kRspOk),
      Only("curve/invalid"));
  ExpectCaught(r, "SS-CURVE-002");
  ExpectMustsFailed(r, {"SS-CURVE-002"});
}

TEST(StackshotProofs, ACurveStartingAfterThePreviousEndsAcceptedIsCaughtByCurve003) {
  const RunReport r = RunBroken(MotionConfigAnswered(
                                    [](const stackshot::MotionConfig& m) {
                                      for (size_t k = 1; k < m.curves.size(); ++k) {
                                        const float x0 = m.curves[k].p[0].x.value();
                                        if (x0 == 0.0f) break;
                                        if (x0 != m.curves[k - 1].p[3].x.value()) return true;
                                      }
                                      return false;
                                    },
                                    Action::kRspOk),
                                Only("curve/invalid"));
  ExpectCaught(r, "SS-CURVE-003");
  ExpectMustsFailed(r, {"SS-CURVE-003"});
}

TEST(StackshotProofs, AControlPointOutsideItsCurvesTimeAcceptedIsCaughtByCurve004) {
  const RunReport r = RunBroken(
      MotionConfigAnswered(
          [](const stackshot::MotionConfig& m) {
            for (const auto& c : m.curves) {
              if (c.p[1].x.value() < c.p[0].x.value() || c.p[2].x.value() > c.p[3].x.value())
                return true;
            }
            return false;
          },
          Action::kRspOk),
      Only("curve/invalid"));
  ExpectCaught(r, "SS-CURVE-004");
  ExpectMustsFailed(r, {"SS-CURVE-004"});
}

TEST(StackshotProofs, ASplinePlayedAtTwiceItsSpeedIsCaughtByCurve005) {
  // Every time of every CC_MOTION_CONFIG is halved before the controller
  // reads it: each spline is still valid, ends on its last keyframe, and is
  // over in half the time.
  const RunReport r = RunBroken(
      PassThrough, Only("curve/play"), OnRequest(Command::kMotionConfig, [](const Packet& p) {
        return std::optional<Packet>(EditRequest<stackshot::MotionConfig>(p, [](auto& m) {
          for (auto& c : m.curves) {
            for (auto& q : c.p) q.x = q.x.value() / 2;
          }
        }));
      }));
  ExpectCaught(r, "SS-CURVE-005");
  ExpectMustsFailed(r, {"SS-CURVE-005"});
}

}  // namespace
}  // namespace moco::conformance
