// libFuzzer target for the DMC v2 codec (dmc-v2-protocol.txt "Message Format",
// "Message Types"): arbitrary bytes through FrameDecoder in data-derived chunk
// sizes; every frame decoded as a host and as a device message; every decoded
// message must re-encode to the same frame data and decode to the same value;
// every byte must be in a good frame or a skipped count; and, when the first
// byte's bit 7 is set, the chunked event stream must equal the unchunked one.
#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include "wire/dmc.h"

namespace moco::dmc {
namespace {

void Require(bool condition) {
  if (!condition) std::abort();
}

template <class Message, class DecodeFn>
void CheckMessage(const FrameRef& f, const Result<Message>& m, DecodeFn decode) {
  if (!m.ok()) return;
  Require(TypeOf(*m) == f.type);
  const Bytes bytes = Encode(f.id, *m);
  const auto frame = DecodeFrame(bytes);
  Require(frame.ok());
  Require(frame->id == f.id && frame->type == f.type);
  Require(frame->data.size() == f.data.size() &&
          std::equal(frame->data.begin(), frame->data.end(), f.data.begin()));
  const auto again = decode(*frame);
  Require(again.ok() && *again == *m);
}

// Folds an event into a running digest, so that two runs can be compared
// without storing their events.
uint64_t Mix(uint64_t h, uint64_t v) { return (h ^ v) * 0x100000001b3ull; }

uint64_t Digest(uint64_t h, const FrameEvent& e) {
  if (const auto* f = std::get_if<FrameRef>(&e)) {
    h = Mix(h, 1);
    h = Mix(h, f->id);
    h = Mix(h, f->type);
    h = Mix(h, f->data.size());
    return Mix(h, Fletcher16(f->data));
  }
  if (const auto* c = std::get_if<ChecksumError>(&e)) {
    return Mix(Mix(Mix(Mix(h, 2), c->id), c->type), c->length);
  }
  const auto& g = std::get<FramingError>(e);
  h = Mix(h, 3 + static_cast<uint64_t>(g.kind));
  return Mix(Mix(Mix(Mix(h, g.bytes), g.length), g.id), g.type);
}

}  // namespace
}  // namespace moco::dmc

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace moco::dmc;
  if (size == 0) return 0;
  const uint8_t pattern = data[0];
  const ByteView stream(data + 1, size - 1);
  // Bits 5 and 6 of the pattern byte pick the receiver: a 2048-byte buffer
  // (FACTS: dmc-lite) and dropping rejected candidates without rescanning.
  FrameDecoderOptions options;
  if ((pattern & 0x20) != 0) options.max_frame_bytes = 2048;
  options.rescan_rejected = (pattern & 0x40) == 0;

  uint64_t chunked = 0;
  size_t accounted = 0;
  auto on_event = [&](const FrameEvent& e) {
    chunked = Digest(chunked, e);
    if (const auto* f = std::get_if<FrameRef>(&e)) {
      accounted += f->raw.size();
      Require(f->raw.size() == kHeaderSize + f->data.size() + kCheckSize);
      Require(f->data.size() <= options.max_frame_bytes - kHeaderSize - kCheckSize);
      CheckMessage(*f, DecodeHostMessage(f->type, f->data),
                   [](const Frame& fr) { return DecodeHostMessage(fr); });
      // A receiver ignoring trailing bytes reads a leading part of the data.
      const auto lenient = DecodeHostMessage(f->type, f->data, TrailingBytes::kIgnore);
      if (lenient.ok()) {
        Bytes again;
        EncodeData(*lenient, again);
        Require(again.size() <= f->data.size() &&
                std::equal(again.begin(), again.end(), f->data.begin()));
      }
      CheckMessage(*f, DecodeDeviceMessage(f->type, f->data),
                   [](const Frame& fr) { return DecodeDeviceMessage(fr); });
    } else if (const auto* g = std::get_if<FramingError>(&e)) {
      if (g->kind == FramingError::Kind::kSkipped) accounted += g->bytes;
    }
  };
  FrameDecoder dec(options);
  size_t pos = 0;
  for (size_t k = 0; pos < stream.size(); ++k) {
    const size_t n = std::min<size_t>(1 + ((pattern ^ (k * 37)) % 97), stream.size() - pos);
    dec.Feed(stream.subspan(pos, n), on_event);
    Require(dec.pending_bytes() < options.max_frame_bytes);
    pos += n;
  }
  dec.Finish(on_event);
  Require(accounted == stream.size());

  // Bit 7 of the pattern byte asks for the unchunked run to compare with
  // (half the inputs, so that the plain path keeps a high exec rate).
  if ((pattern & 0x80) == 0) return 0;
  uint64_t whole = 0;
  FrameDecoder once(options);
  auto digest = [&whole](const FrameEvent& e) { whole = Digest(whole, e); };
  once.Feed(stream, digest);
  once.Finish(digest);
  Require(whole == chunked);
  return 0;
}
