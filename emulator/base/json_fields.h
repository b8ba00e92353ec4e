// Reading the fields of a JSON object (profiles, rig profiles, run files,
// saved device state, control commands): required and optional fields with
// types and ranges, unknown keys refused, and a problem that names the field
// by its path ("motors[2].max_speed") and says what to write instead.
#ifndef MOCO_BASE_JSON_FIELDS_H_
#define MOCO_BASE_JSON_FIELDS_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace moco::base {

// One refused field. The parts let a caller word the message its own way;
// Message() words it the house way.
struct FieldProblem {
  enum class Kind {
    kNotObject,  // the object being read is not a JSON object
    kMissing,    // a required field is absent
    kType,       // a field of the wrong type
    kRange,      // the right type, but outside its range (or too long)
    kUnknown,    // a key that no read asked for
    kOther,      // the caller's own complaint (JsonFields::Fail)
  };
  Kind kind = Kind::kOther;
  // The field's path: "limits.motor_count", "motors[2].max_speed"; for
  // kNotObject the object's own path ("" for the top level).
  std::string field;
  // kMissing, kType: what the field must hold ("an integer 0..32",
  // "true or false", "a string", "an object").
  std::string expected;
  // kType, kNotObject: what it holds instead ("a string", "an integer").
  std::string found;
  // kType, kRange: the value as written, shortened to about 40 characters.
  std::string value;
  // The complaint ("is 40, outside 0..32") and the fix ("use a value in
  // 0..32, or remove the field to use the default 16").
  std::string problem;
  std::string fix;

  // `field "limits.motor_count" is 40, outside 0..32; use a value in ...`;
  // for kNotObject `motors[2] must be a JSON object, found ...; write ...`.
  std::string Message() const;
};

// Whether a field may be left out.
enum class Presence { kOptional, kRequired };
inline constexpr Presence kOptional = Presence::kOptional;
inline constexpr Presence kRequired = Presence::kRequired;

// "a string", "an integer", "a number", "a boolean", "a array", ... (the
// article of nlohmann's type names, kept as the messages have it).
std::string JsonTypeName(const nlohmann::json& v);

// Reads the fields of one JSON object. The first problem is kept (shared with
// the readers of nested objects) and reads after it return their defaults, so
// a caller may read every field and look once; or check failed() after each
// read and stop (throw) at the first. An absent optional object (Child) reads
// as all defaults, with no field required.
class JsonFields {
 public:
  // `path` is the object's place in the document ("" for the top level,
  // "motors[2]"); `doc` is where its fields are described, named when a key
  // is unknown ("": the known keys are listed instead). REQUIRES: `object`
  // outlives the reader and the readers it makes. A non-object is a problem
  // (kNotObject) at once.
  explicit JsonFields(const nlohmann::json& object, std::string path = "", std::string doc = "");

  bool failed() const { return problem_->has_value(); }
  // REQUIRES: failed().
  const FieldProblem& problem() const { return **problem_; }
  // The kept problem, forgotten (here and in the readers sharing it), so that
  // a caller that reports each problem as it comes may read on.
  std::optional<FieldProblem> TakeProblem();

  bool Has(std::string_view key) const;
  // The path of `key` in this object: "motors[2].max_speed".
  std::string FieldName(std::string_view key) const;
  const std::string& path() const { return path_; }

  // Each read returns `def` when the key is absent (a problem first when
  // kRequired) or holds a refused value.
  // A whole number min..max; a float with no fraction (4.0) counts as one.
  int64_t Int(std::string_view key, int64_t def, int64_t min, int64_t max,
              Presence presence = kOptional);
  // A finite number min..max; `unit` ("m", "N m/rad") goes into the fix.
  double Number(std::string_view key, double def, double min, double max,
                Presence presence = kOptional, std::string_view unit = {});
  bool Bool(std::string_view key, bool def, Presence presence = kOptional);
  // max_bytes: the longest UTF-8 text accepted (0: no limit).
  std::string String(std::string_view key, std::string_view def, size_t max_bytes = 0,
                     Presence presence = kOptional);
  // An unsigned 32-bit value written as a number or a "0x..." hex string.
  uint32_t Bits32(std::string_view key, uint32_t def, Presence presence = kOptional);
  // One of `choices` (strings); its index, or nullopt when absent or refused.
  std::optional<size_t> Choice(std::string_view key, std::span<const std::string_view> choices,
                               Presence presence = kOptional);
  // An array of min_count..max_count finite numbers, each min..max; empty
  // when absent or refused.
  std::vector<double> Numbers(std::string_view key, double min, double max, size_t min_count,
                              size_t max_count, Presence presence = kOptional);
  // The value of `key` as it is, marked as read; nullptr when absent.
  const nlohmann::json* Raw(std::string_view key);
  // An array (any elements); nullptr when absent or not an array.
  const nlohmann::json* Array(std::string_view key, Presence presence = kOptional);
  // A reader for the object at `key`, sharing this reader's problem.
  JsonFields Child(std::string_view key, Presence presence = kOptional);
  // A reader for element `index` of the array at `key` ("obstacles[0]").
  // REQUIRES: Array(key) returned an array of more than `index` elements.
  JsonFields Item(std::string_view key, size_t index);

  // Refuses the first key that no read (Has excepted) asked for.
  void Finish();
  // Records the caller's own complaint about `key` ("" for the object itself)
  // unless a problem is already kept.
  void Fail(std::string_view key, std::string_view problem, std::string_view fix);

 private:
  JsonFields(const nlohmann::json* object, std::string path, std::string doc,
             std::shared_ptr<std::optional<FieldProblem>> problem);
  const nlohmann::json* Find(std::string_view key);
  void Keep(FieldProblem p);
  // A problem of `kind` at `key`, unless one is kept already.
  void Refuse(FieldProblem::Kind kind, std::string_view key, const nlohmann::json* v,
              std::string expected, std::string problem, std::string fix);
  void Missing(std::string_view key, const std::string& expected);

  const nlohmann::json* object_;  // nullptr: absent (all defaults) or refused
  std::string path_;
  std::string doc_;
  std::vector<std::string> read_;
  std::shared_ptr<std::optional<FieldProblem>> problem_;
};

// Parses `text` as nlohmann::json::parse does (throwing its parse_error and,
// for a number beyond a double, its out_of_range), and notes in `duplicate`
// the path ("motors[].max_speed") of the first key given twice in one object,
// which the parser would otherwise settle silently by the last one; "" when
// none. `at`, when given, is left holding the path of the value the parser
// reached last (for naming the field of a refused number). With
// `ignore_comments`, // and /* */ comments are allowed.
nlohmann::json ParseJsonNotingDuplicateKeys(std::string_view text, std::string& duplicate,
                                            std::string* at = nullptr,
                                            bool ignore_comments = false);

}  // namespace moco::base

#endif  // MOCO_BASE_JSON_FIELDS_H_
