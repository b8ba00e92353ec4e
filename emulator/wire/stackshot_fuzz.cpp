// libFuzzer target for the StackShot binary codec (stackshot-protocol.txt
// section 2): arbitrary bytes through the streaming decoder of both
// directions, then typed decode; every value that decodes must re-encode and
// decode again to an equal value. (Bytes may differ only where decoding
// normalises: a bool_t byte other than 0 reads as true and encodes as 1.)
#include <cstdio>
#include <cstdlib>

#include "wire/stackshot.h"

namespace {

using moco::stackshot::Bytes;
using moco::stackshot::ByteView;
using moco::stackshot::DecodedPacket;
using moco::stackshot::Packet;
using moco::stackshot::PacketDecoder;

[[noreturn]] void Fail(const char* what, const Packet& p) {
  std::fprintf(stderr, "stackshot_fuzz: %s: %s\n", what, moco::stackshot::Describe(p).c_str());
  std::abort();
}

void CheckPacket(const Packet& p) {
  namespace ss = moco::stackshot;
  Bytes frame;
  if (!ss::EncodePacket(p, frame)) Fail("decoded packet does not re-encode", p);
  auto again = ss::DecodePacket(frame);
  if (!again.ok() || !(*again == p)) Fail("packet round trip differs", p);

  if (p.from_device) {
    auto reply = ss::DecodeDevicePacket(p);
    if (!reply.ok()) return;
    ss::ReplyContext context;
    if (reply->kind == ss::ReplyKind::kReadResponse) context.request_action = ss::Action::kRead;
    if (reply->kind == ss::ReplyKind::kWriteAck) context.request_action = ss::Action::kWrite;
    Packet re = ss::ToPacket(*reply);
    re.checksum = p.checksum;
    if (re.command != p.command || re.data.size() != p.data.size()) {
      Fail("device reply re-encodes to a different layout", p);
    }
    auto back = ss::DecodeDevicePacket(re, context);
    if (!back.ok() || !(*back == *reply)) Fail("device reply round trip differs", p);
    (void)ss::Describe(*reply);
  } else {
    auto command = ss::DecodeHostPacket(p);
    if (!command.ok()) {
      (void)ss::ErrorReplyStatus(command.error());
      return;
    }
    Packet re = ss::ToPacket(*command);
    re.checksum = p.checksum;
    if (re.command != p.command || re.data.size() != p.data.size()) {
      Fail("host command re-encodes to a different layout", p);
    }
    auto back = ss::DecodeHostPacket(re);
    if (!back.ok() || !(*back == *command)) Fail("host command round trip differs", p);
    if (const auto* m = std::get_if<ss::MotionConfig>(&command->payload)) {
      (void)ss::ValidateMotionConfig(*m);
    }
    (void)ss::Describe(*command);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const ByteView input(data, size);
  // The first byte picks a chunk size so that chunking is exercised too.
  const size_t chunk = size == 0 ? 1 : 1 + data[0] % 64;
  for (bool from_device : {false, true}) {
    PacketDecoder decoder(from_device);
    std::vector<DecodedPacket> packets;
    for (size_t pos = 0; pos < size; pos += chunk) {
      decoder.Feed(input.subspan(pos, std::min(chunk, size - pos)), packets);
      if (decoder.pending_bytes() >= moco::stackshot::kMaxPacketBytes) std::abort();
    }
    for (const DecodedPacket& d : packets) CheckPacket(d.packet);
  }
  (void)moco::stackshot::SplitForWifi(input);
  return 0;
}
