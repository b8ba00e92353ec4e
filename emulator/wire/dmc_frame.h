// DMC v2 framing (dmc-v2-protocol.txt "Message Format" and "Computing and
// Validating the Checksum"; ERRATA dmc 1.1, 1.2): Fletcher-16 check bytes,
// frame encode/decode and a streaming decoder with resynchronisation.
#ifndef MOCO_WIRE_DMC_FRAME_H_
#define MOCO_WIRE_DMC_FRAME_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "wire/bytes.h"
#include "wire/dmc_constants.h"

namespace moco::dmc {

using wire::Bytes;
using wire::ByteView;
using wire::DecodeError;
using wire::Result;

// The spec's computeChecksum(): Fletcher-16 over `bytes`, sums reduced mod 255
// after every block of 20 bytes. Returns (sum2 << 8) | sum1, each in 0..254.
uint16_t Fletcher16(ByteView bytes);

// The two check bytes {c0, c1} the spec appends to a message whose
// Fletcher16() is `sum`, so that Fletcher16(message + c0 + c1) == 0.
// Both bytes are in 1..255.
std::array<uint8_t, 2> CheckBytes(uint16_t sum);

// ERRATA 1.1: a received frame is valid iff the checksum over all of it
// (marker through check bytes) is zero. Checks nothing else.
inline bool ChecksumIsZero(ByteView frame) { return Fletcher16(frame) == 0; }

// One frame with its data section copied out.
struct Frame {
  uint32_t id = 0;
  uint16_t type = 0;  // as on the wire, kFlagAck included
  Bytes data;         // at most kMaxDataLength bytes in a valid frame

  bool operator==(const Frame&) const = default;
};

// A frame seen by FrameDecoder, without copying. The views point into the
// decoder's buffer or into the chunk being fed and are valid only during the
// event callback that delivers them.
struct FrameRef {
  uint32_t id = 0;
  uint16_t type = 0;
  ByteView data;  // the data section
  ByteView raw;   // the whole frame, marker through check bytes

  Frame ToFrame() const { return Frame{id, type, Bytes(data.begin(), data.end())}; }
};

// Appends one complete frame (marker, header, data, check bytes) to `out`.
// REQUIRES: data.size() <= kMaxDataLength for a frame a receiver accepts.
// Longer data (up to 0xffff bytes) is still written with its true Length so
// that tests can build oversize frames; beyond 0xffff it is cut to 0xffff.
void EncodeFrame(uint32_t id, uint16_t type, ByteView data, Bytes& out);
inline void EncodeFrame(const Frame& f, Bytes& out) { EncodeFrame(f.id, f.type, f.data, out); }
Bytes EncodeFrame(const Frame& f);

// Building a frame in place, for encoders that append the data section
// themselves: BeginFrame writes marker, ID, Type and a Length placeholder and
// returns the frame's start offset; EndFrame fills Length from the bytes
// appended since (cut to 0xffff) and appends the check bytes.
size_t BeginFrame(uint32_t id, uint16_t type, Bytes& out);
void EndFrame(size_t start, Bytes& out);

// The header fields of a frame that starts at bytes[0] (marker 'D' 'F' and a
// whole header present), whatever follows; nullopt otherwise. For tools that
// take messages apart without judging them (the fuzz mutator, replay).
struct FrameHeader {
  uint32_t id = 0;
  uint16_t type = 0;
  uint16_t length = 0;  // as declared
};
std::optional<FrameHeader> PeekHeader(ByteView bytes);
// The size of the whole frame at bytes[0]: a header whose Length is at most
// kMaxDataLength and every byte through the check bytes present; 0 otherwise.
// The checksum is not verified.
size_t WholeFrameAt(ByteView bytes);

// Decodes exactly one complete frame. Errors (offsets from the first byte of
// `bytes`): kTruncated (fewer than header + Length + 2 bytes), kBadValue
// (marker is not 'D' 'F'), kBadLength (Length > kMaxDataLength), kTrailing
// (bytes after the check bytes), kBadChecksum (checksum over the frame != 0).
Result<Frame> DecodeFrame(ByteView bytes);

// FrameDecoder events ----------------------------------------------------------

// A frame whose marker and Length were plausible but whose checksum is not
// zero. Carries the header fields as received so that the device can answer
// ACK ERR_CHECKSUM with the request's ID and Type (they may be the corrupted
// fields themselves: the checksum cannot say which byte was hit). Whether the
// candidate was a message at all (or a false "DF" in noise) is for the
// receiver to judge from the header; see PlausibleRequestHeader().
struct ChecksumError {
  uint32_t id = 0;
  uint16_t type = 0;
  uint16_t length = 0;

  bool operator==(const ChecksumError&) const = default;
};

// Bytes dropped from the stream or a candidate frame given up on.
struct FramingError {
  enum class Kind : uint8_t {
    // `bytes` stream bytes were not part of any good frame: noise before a
    // marker, a lone 'D', or the bytes of a rejected candidate that did not
    // turn out to start a later frame. Reported once, just before the next
    // other event (or by Finish()), so the count does not depend on chunking.
    kSkipped,
    // A header declared `length` above the decoder's max_data_length()
    // (ERRATA 1.2). Nothing is allocated; the scan resumes after the
    // candidate's 'D' (or after its header without rescan).
    kOversize,
    // Only from Finish(): the stream ended inside a candidate frame that had
    // `bytes` bytes (`length` as declared, 0 when the header was not
    // complete). The scan resumes after the candidate's 'D' (or the
    // candidate's bytes are dropped without rescan).
    kTruncated,
  };
  Kind kind = Kind::kSkipped;
  size_t bytes = 0;
  uint16_t length = 0;
  uint32_t id = 0;    // kOversize and kTruncated with a complete header
  uint16_t type = 0;  // ditto

  bool operator==(const FramingError&) const = default;
};

// What the decoder hands to its callback.
using FrameEvent = std::variant<FrameRef, ChecksumError, FramingError>;
// The same with the frame copied out, for collecting events.
using StreamEvent = std::variant<Frame, ChecksumError, FramingError>;
StreamEvent ToStreamEvent(const FrameEvent& e);

// Whether a header whose frame failed its checksum (or never completed) can
// be a request a host sent, so that answering it ACK ERR_CHECKSUM answers a
// message and not a false "DF" in noise: no ACK flag (a host's ACK is never
// answered, "MSG_FLAG_ACK") and a Type within kReferenceTypeMask (the
// reference host's own parser drops any other type, FACTS). The Length is
// already known to fit the receiver (the decoder calls anything else
// kOversize). A random header passes with a chance of about 1 in 64.
constexpr bool PlausibleRequestHeader(uint16_t type) {
  return (type & kFlagAck) == 0 && HasReferenceParserType(type);
}

// How a FrameDecoder bounds and resynchronises; the defaults are the spec's
// receiver.
struct FrameDecoderOptions {
  // The largest frame (header + data + check bytes) taken whole: a Length
  // above max_frame_bytes - 12 is kOversize. "The receiving buffer on the
  // device must be at least 1048 bytes": the default is that minimum; a
  // device may hold more (FACTS: dmc-lite, 2048). Clamped to
  // kHeaderSize + kCheckSize .. kLargestReceiveBuffer.
  size_t max_frame_bytes = kMaxFrameSize;
  // After a rejected candidate (oversize or checksum failure) the scan
  // resumes at the byte after its 'D', so a real frame inside a false "DF"
  // is still found. false: every byte of the candidate the decoder read (the
  // header of an oversize one, the whole frame of a checksum failure, the
  // pending bytes at Finish()) is dropped, as the reference parser does
  // (FACTS). A 'D' not followed by 'F' always resumes at the next byte.
  bool rescan_rejected = true;
};

// Streaming decoder: push interface with a callback.
//
//   FrameDecoder dec;                                     // or dec(options)
//   dec.Feed(chunk, [&](const FrameEvent& e) { ... });   // any chunking
//   dec.Finish(callback);                                 // end of stream / idle line
//
// Events come in stream order and are a function of the byte stream alone,
// not of how it was chunked. Resynchronisation, as the reference parser does
// it: hunt for 'D' then 'F'; read the 10-byte header; a Length above
// max_data_length() is kOversize; when header + Length + 2 bytes are there, a
// zero checksum gives a frame, otherwise ChecksumError. After kOversize or a
// ChecksumError the scan resumes at the byte AFTER the candidate's 'D', so a
// real frame swallowed by a false "DF" in noise is still found (unless
// options.rescan_rejected is false). Once Finish() has run, every stream byte
// is in exactly one good frame or one kSkipped count.
//
// Frame types with bits outside kReferenceTypeMask are delivered (the device
// must answer them with ERR_UNSUPPORTED); see HasReferenceParserType().
//
// Memory: a fixed member buffer of kLargestReceiveBuffer bytes holds only an
// incomplete candidate frame (never more than max_frame_bytes - 1 bytes).
// Frames wholly inside a fed chunk are checked in place and handed out as
// views without copying; nothing is allocated, whatever the options.
class FrameDecoder {
 public:
  explicit FrameDecoder(FrameDecoderOptions options = {});

  // The largest Length taken (max_frame_bytes - 12).
  size_t max_data_length() const { return max_data_length_; }
  bool rescan_rejected() const { return rescan_; }

  // Consumes all of `chunk`, calling on_event(const FrameEvent&) for each
  // event completed by it. The callback must not call back into this decoder.
  template <typename F>
  void Feed(ByteView chunk, F&& on_event) {
    FeedImpl(chunk, &Thunk<std::remove_reference_t<F>>, Context(on_event));
  }

  // The stream ended (or the line has been idle long enough that the pending
  // bytes will not be completed): gives up on the pending candidate (kTruncated),
  // rescans its bytes, reports what it finds and the final kSkipped count, and
  // leaves the decoder as if newly constructed.
  template <typename F>
  void Finish(F&& on_event) {
    FinishImpl(&Thunk<std::remove_reference_t<F>>, Context(on_event));
  }

  // Forgets pending bytes and the skipped count without reporting them.
  void Reset() {
    buf_len_ = 0;
    skipped_ = 0;
  }

  // Bytes of an incomplete candidate frame held since the last Feed().
  size_t pending_bytes() const { return buf_len_; }
  // Bytes skipped but not yet reported in a kSkipped event.
  size_t unreported_skipped_bytes() const { return skipped_; }

 private:
  using Sink = void (*)(void* ctx, const FrameEvent& e);
  template <typename F>
  static void* Context(F& f) {
    return const_cast<void*>(static_cast<const void*>(std::addressof(f)));
  }
  template <typename F>
  static void Thunk(void* ctx, const FrameEvent& e) {
    (*static_cast<F*>(ctx))(e);
  }

  enum class Step : uint8_t { kNeedMore, kReject, kGood };
  // Examines the candidate at p[0] == 'D' with `avail` bytes at hand. Sets
  // `need` to the bytes needed (kNeedMore), the frame size (kGood) or the
  // bytes to drop before the scan resumes (kReject: 1 with rescan).
  Step Examine(const uint8_t* p, size_t avail, size_t& need, Sink sink, void* ctx);
  void Emit(const FrameEvent& e, Sink sink, void* ctx);
  // Scans a contiguous span starting in direct mode. With at_end, a candidate
  // that needs more bytes than the span has is given up instead of buffered.
  void ScanSpan(const uint8_t* p, size_t n, bool at_end, Sink sink, void* ctx);
  void FeedImpl(ByteView chunk, Sink sink, void* ctx);
  void FinishImpl(Sink sink, void* ctx);

  size_t max_data_length_ = kMaxDataLength;
  bool rescan_ = true;
  // Bytes [0, buf_len_) are the pending candidate, buf_[0] == 'D'; the rest is
  // never read, so it is left uninitialised.
  std::array<uint8_t, kLargestReceiveBuffer> buf_;
  size_t buf_len_ = 0;
  size_t skipped_ = 0;
};

// Runs a fresh FrameDecoder over `stream` in one chunk, then Finish() when
// `finish`, collecting owned events (allocates: for tests and tools).
std::vector<StreamEvent> DecodeStream(ByteView stream, bool finish = true,
                                      FrameDecoderOptions options = {});

}  // namespace moco::dmc

#endif  // MOCO_WIRE_DMC_FRAME_H_
