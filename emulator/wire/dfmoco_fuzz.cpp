// Fuzz target for the DFMoco ASCII codec (dfmoco-protocol.txt "Messages", FACTS "DFMoco",
// stackshot-protocol.txt section 3): bytes -> LineFramer (both terminations) -> host and
// device parsers for every dialect. Aborts when a parsed message does not re-format and
// re-parse to the same value, when the framer exceeds its bound, or when two chunkings of
// the same bytes frame differently.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

#include "wire/dfmoco.h"

namespace {

using moco::dfmoco::Dialect;
using moco::dfmoco::FrameEvent;
using moco::dfmoco::LineFramer;
using moco::dfmoco::LineTermination;

void Require(bool ok) {
  if (!ok) std::abort();
}

std::string_view Body(const std::string& text) {
  Require(text.size() >= 2 && text.compare(text.size() - 2, 2, "\r\n") == 0);
  return std::string_view(text).substr(0, text.size() - 2);
}

void CheckLine(std::string_view line, const Dialect& dialect) {
  const auto host = moco::dfmoco::ParseHostLine(line, dialect);
  if (host.ok()) {
    const std::string text = moco::dfmoco::FormatHost(*host);
    const auto again = moco::dfmoco::ParseHostLine(Body(text), dialect);
    Require(again.ok() && *again == *host);
    Require(!moco::dfmoco::Describe(*host).empty());
  } else {
    Require(host.error().offset <= line.size());
    (void)moco::dfmoco::ErrorReply(host.error());
  }
  const auto device = moco::dfmoco::ParseDeviceLine(line, dialect);
  if (device.ok()) {
    const std::string text = moco::dfmoco::FormatDevice(*device);
    const auto again = moco::dfmoco::ParseDeviceLine(Body(text), dialect);
    Require(again.ok() && *again == *device);
    Require(!moco::dfmoco::Describe(*device, dialect).empty());
  } else {
    Require(device.error().offset <= line.size());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const Dialect kDialects[] = {moco::dfmoco::Dfmoco2(4), moco::dfmoco::Dfmoco1("1.2.7", 8),
                                      moco::dfmoco::StackShot3x()};
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  // A small bound as well as the real one, so overflow is reached often.
  for (const size_t bound : {moco::dfmoco::kMaxLineBytes, size_t{16}}) {
    for (const auto mode : {LineTermination::kSketch, LineTermination::kLenient}) {
      LineFramer whole({mode, bound});
      const auto expected = whole.Feed(bytes);
      // The same bytes in two chunks, split where the first byte says.
      LineFramer split({mode, bound});
      const size_t at = size == 0 ? 0 : data[0] % (size + 1);
      auto got = split.Feed(bytes.substr(0, at));
      for (auto& e : split.Feed(bytes.substr(at))) got.push_back(std::move(e));
      Require(got == expected);
      Require(whole.buffered() <= bound && split.buffered() == whole.buffered());
      for (const auto& e : expected) {
        Require(e.kind == FrameEvent::Kind::kOverflow ? e.text.size() == bound
                                                      : e.text.size() <= bound);
        if (bound != moco::dfmoco::kMaxLineBytes) continue;
        for (const Dialect& d : kDialects) CheckLine(e.text, d);
      }
    }
  }
  // The whole input as one line, terminators and all.
  for (const Dialect& d : kDialects) CheckLine(bytes, d);
  return 0;
}
