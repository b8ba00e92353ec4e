// A value or the reason there is none: the one result type of the project.
// The error is a message by default; the codecs carry a structured error
// (wire::DecodeError) and the rig profiles the field and the message.
#ifndef MOCO_BASE_RESULT_H_
#define MOCO_BASE_RESULT_H_

#include <string>
#include <type_traits>
#include <utility>
#include <variant>

namespace moco::base {

template <typename T, typename E = std::string>
class Result {
  static_assert(!std::is_same_v<T, E>, "a Result's value and error types must differ");

 public:
  Result(T value) : v_(std::in_place_index<0>, std::move(value)) {}  // NOLINT: implicit by design
  Result(E error) : v_(std::in_place_index<1>, std::move(error)) {}  // NOLINT: implicit by design

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  // REQUIRES: ok().
  const T& value() const& { return std::get<0>(v_); }
  T& value() & { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  const T& operator*() const& { return value(); }
  const T* operator->() const { return &value(); }

  // REQUIRES: !ok().
  const E& error() const { return std::get<1>(v_); }

 private:
  std::variant<T, E> v_;
};

}  // namespace moco::base

#endif  // MOCO_BASE_RESULT_H_
