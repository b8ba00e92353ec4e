// Reading device profiles (fixtures/profiles/*.json): typed fields with
// defaults and ranges, and start-up errors that name the field and the fix
// (ARCHITECTURE house style 6: start-up errors are exceptions with a message
// a user can act on).
#ifndef MOCO_DEVICES_PROFILE_H_
#define MOCO_DEVICES_PROFILE_H_

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "base/json_fields.h"

namespace moco::devices {

// A profile that cannot be used. what() names the file, the field, what was
// found and what to write instead.
class ProfileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads one JSON object of a profile: base::JsonFields that throws
// ProfileError at the first problem, prefixed with `where`. Every Get*
// returns the default when the key is absent and throws when present with
// the wrong type or out of range. Finish() throws for keys nobody read (a typo
// such as "motor_cout" must not silently fall back to a default).
class ProfileReader {
 public:
  // `where` prefixes messages, e.g. "profile fixtures/profiles/dmc16.json".
  // `path` is the object's location inside the document ("" for the root,
  // "motors[2]" for a nested object). `doc` is where the fields are described
  // (a misspelt key points there). REQUIRES: `object` outlives the reader.
  ProfileReader(const nlohmann::json& object, std::string where, std::string path = "",
                std::string doc = "docs/profiles.md");

  bool Has(std::string_view key) const { return fields_.Has(key); }
  int64_t GetInt(std::string_view key, int64_t def, int64_t min, int64_t max);
  double GetNumber(std::string_view key, double def, double min, double max);
  bool GetBool(std::string_view key, bool def);
  // max_bytes: the longest UTF-8 text accepted (0 = unlimited).
  std::string GetString(std::string_view key, std::string_view def, size_t max_bytes = 0);
  // An unsigned value written as a number or as a "0x..." hex string.
  uint32_t GetFlags(std::string_view key, uint32_t def);
  // A nested object or array (null json when absent); marks the key as read.
  const nlohmann::json& GetRaw(std::string_view key);
  // A reader for a nested object. Throws when present and not an object.
  ProfileReader Child(std::string_view key);

  // Throws ProfileError naming the first key that was never read.
  void Finish();

  // A ProfileError for `key` with the given complaint and fix.
  [[noreturn]] void Fail(std::string_view key, std::string_view problem, std::string_view fix);
  const std::string& where() const { return where_; }
  std::string FieldName(std::string_view key) const { return fields_.FieldName(key); }

 private:
  ProfileReader(base::JsonFields fields, std::string where);
  // Throws the problem the reader has kept, if any.
  void Check();
  // `x` once Check() has passed.
  template <typename T>
  T Checked(T x) {
    Check();
    return x;
  }

  base::JsonFields fields_;
  std::string where_;
};

// Parses `text` as a JSON object; a syntax error throws ProfileError with the
// byte offset. `where` as for ProfileReader.
nlohmann::json ParseProfileText(std::string_view text, const std::string& where);

// Reads and parses a profile file; `where` becomes "profile <path>" (returned
// through where_out for the field errors that follow). Throws ProfileError
// for an unreadable file or bad JSON.
nlohmann::json ReadProfileFile(const std::string& path, std::string* where_out = nullptr);

}  // namespace moco::devices

#endif  // MOCO_DEVICES_PROFILE_H_
