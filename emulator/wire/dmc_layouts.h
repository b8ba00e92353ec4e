// The DMC v2 codec's field layouts, shared by its two halves (internal to
// emulator/wire): Fields, the reader of a message's data fields that remembers
// the first failure, and one Put (encode) and one Get (decode) per message
// struct, defined in dmc_layouts.cpp and called by the dispatch in dmc.cpp.
#ifndef MOCO_EMULATOR_WIRE_DMC_LAYOUTS_H_
#define MOCO_EMULATOR_WIRE_DMC_LAYOUTS_H_

#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>

#include "wire/bytes.h"
#include "wire/dmc.h"

namespace moco::dmc::layout {

using wire::Reader;
using wire::Writer;

// --- Field reading with the first failure remembered ------------------------------

class Fields {
 public:
  Fields(Reader& r, TrailingBytes trailing, MissingFields missing = MissingFields::kError)
      : r_(r),
        ignore_(trailing == TrailingBytes::kIgnore),
        zero_(missing == MissingFields::kZero) {}
  // Whether an optional field or another list entry of `n` bytes is to be
  // read: strictly, any byte left starts one (a short one is then
  // kTruncated); ignoring trailing bytes, only `n` whole bytes do.
  bool Has(size_t n) const { return ignore_ ? r_.remaining() >= n : !r_.empty(); }
  bool ignoring_trailing() const { return ignore_; }
  Fields& U8(uint8_t& v, const char* name) {
    if (!err_ && !r_.U8(v)) Missing(v, name);
    return *this;
  }
  Fields& U16(uint16_t& v, const char* name) {
    if (!err_ && !r_.U16Le(v)) Missing(v, name);
    return *this;
  }
  Fields& I16(int16_t& v, const char* name) {
    if (!err_ && !r_.I16Le(v)) Missing(v, name);
    return *this;
  }
  Fields& U32(uint32_t& v, const char* name) {
    if (!err_ && !r_.U32Le(v)) Missing(v, name);
    return *this;
  }
  Fields& I32(int32_t& v, const char* name) {
    if (!err_ && !r_.I32Le(v)) Missing(v, name);
    return *this;
  }
  Fields& Optional(std::optional<uint16_t>& v, const char* name) {
    if (!err_ && Has(2)) {
      uint16_t x = 0;
      U16(x, name);
      if (!err_) v = x;
    }
    return *this;
  }
  // START INDEX with the last-set flag split out.
  Fields& StartIndex(uint32_t& index, bool& last, const char* name) {
    uint32_t raw = 0;
    U32(raw, name);
    index = raw & kStartIndexMask;
    last = (raw & kLastSetFlag) != 0;
    return *this;
  }
  // At least one more entry of `n` bytes must follow (a list of "one or more"),
  // unless missing fields read as zero (MissingFields::kZero).
  Fields& NotEmpty(const char* name, size_t n = 1) {
    if (!err_ && !zero_ && !Has(n)) err_ = r_.Truncated(name);
    return *this;
  }
  void Fail(DecodeError e) {
    if (!err_) err_ = std::move(e);
  }
  bool ok() const { return !err_; }
  Reader& reader() { return r_; }
  std::optional<DecodeError>& error() { return err_; }

 private:
  // A field the data lacks: an error, or 0 with the rest of the data consumed.
  template <class T>
  void Missing(T& v, const char* name) {
    if (!zero_) {
      err_ = r_.Truncated(name);
      return;
    }
    v = 0;
    r_.Rest();
  }

  Reader& r_;
  bool ignore_;
  bool zero_;
  std::optional<DecodeError> err_;
};

// --- Layouts: Put (encode) and Get (decode) per struct (dmc_layouts.cpp) ---------------

template <class T>
requires(std::is_empty_v<T>) void Put(Writer&, const T&) {}
template <class T>
requires(std::is_empty_v<T>) void Get(Fields&, T&) {}
void Put(Writer&, const Ack& m);
void Put(Writer&, const Unknown& m);
void Put(Writer&, const VirtAimPoint& m);
void Get(Fields&, VirtAimPoint& m);
void Put(Writer&, const Dmx& m);
void Get(Fields&, Dmx& m);
void Put(Writer&, const GioOut& m);
void Get(Fields&, GioOut& m);
void Put(Writer&, const GioCam& m);
void Get(Fields&, GioCam& m);
void Put(Writer&, const MotorMove& m);
void Get(Fields&, MotorMove& m);
void Put(Writer&, const MotorStop& m);
void Get(Fields&, MotorStop& m);
void Put(Writer&, const MotorStopAll& m);
void Get(Fields&, MotorStopAll& m);
void Put(Writer&, const MotorResetPosition& m);
void Get(Fields&, MotorResetPosition& m);
void Put(Writer&, const MotorJog& m);
void Get(Fields&, MotorJog& m);
void Put(Writer&, const MotorConfigure& m);
void Get(Fields&, MotorConfigure& m);
void Put(Writer&, const MotorSetSpeed& m);
void Get(Fields&, MotorSetSpeed& m);
void Put(Writer&, const MotorSetLimits& m);
void Get(Fields&, MotorSetLimits& m);
void Put(Writer&, const RtUploadMoveBegin& m);
void Get(Fields&, RtUploadMoveBegin& m);
void Put(Writer&, const RtUploadMoveAxis& m);
void Get(Fields&, RtUploadMoveAxis& m);
void Put(Writer&, const RtUploadMoveDmx& m);
void Get(Fields&, RtUploadMoveDmx& m);
void Put(Writer&, const RtUploadMoveTriggers& m);
void Get(Fields&, RtUploadMoveTriggers& m);
void Put(Writer&, const RtPositionFrame& m);
void Get(Fields&, RtPositionFrame& m);
void Put(Writer&, const RtRunMove& m);
void Get(Fields&, RtRunMove& m);
void Put(Writer&, const RtShootFrame& m);
void Get(Fields&, RtShootFrame& m);
void Put(Writer&, const RtShootFrame2& m);
void Get(Fields&, RtShootFrame2& m);
void Put(Writer&, const RtJogAll& m);
void Get(Fields&, RtJogAll& m);
void Put(Writer&, const VirtConfig& m);
void Get(Fields&, VirtConfig& m);
void Put(Writer&, const VirtMove& m);
void Get(Fields&, VirtMove& m);
void Put(Writer&, const VirtStop& m);
void Get(Fields&, VirtStop& m);
void Put(Writer&, const VirtJog& m);
void Get(Fields&, VirtJog& m);
void Put(Writer&, const VirtJogOnLine& m);
void Get(Fields&, VirtJogOnLine& m);
void Put(Writer&, const HiResponse& m);
void Get(Fields&, HiResponse& m);
void Put(Writer&, const MotorStatusResponse& m);
void Get(Fields&, MotorStatusResponse& m);
void Put(Writer&, const MotorMoveResponse& m);
void Get(Fields&, MotorMoveResponse& m);
void Put(Writer&, const MotorPositionReport& m);
void Get(Fields&, MotorPositionReport& m);
void Put(Writer&, const GioInReport& m);
void Get(Fields&, GioInReport& m);
void Put(Writer&, const MotorHardStop& m);
void Get(Fields&, MotorHardStop& m);
void Put(Writer&, const VirtPositionReport& m);
void Get(Fields&, VirtPositionReport& m);

}  // namespace moco::dmc::layout

#endif  // MOCO_EMULATOR_WIRE_DMC_LAYOUTS_H_
