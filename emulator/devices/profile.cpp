// Profile fields read through base::JsonFields, refusals thrown as ProfileError
// (see profile.h); profile files read and parsed.
#include "devices/profile.h"

#include <string>
#include <utility>
#include <vector>

#include "base/file_io.h"
#include "base/json_fields.h"

namespace moco::devices {

ProfileReader::ProfileReader(const nlohmann::json& object, std::string where, std::string path,
                             std::string doc)
    : ProfileReader(base::JsonFields(object, std::move(path), std::move(doc)), std::move(where)) {}

ProfileReader::ProfileReader(base::JsonFields fields, std::string where)
    : fields_(std::move(fields)), where_(std::move(where)) {
  Check();
}

void ProfileReader::Check() {
  // Taken, not kept: the reader stays usable after a refusal.
  if (std::optional<base::FieldProblem> p = fields_.TakeProblem()) {
    throw ProfileError(where_ + ": " + p->Message());
  }
}

void ProfileReader::Fail(std::string_view key, std::string_view problem, std::string_view fix) {
  fields_.Fail(key, problem, fix);  // recorded: every read before took its problem
  Check();
  throw ProfileError(where_ + ": field \"" + FieldName(key) + "\" " + std::string(problem));
}

int64_t ProfileReader::GetInt(std::string_view key, int64_t def, int64_t min, int64_t max) {
  return Checked(fields_.Int(key, def, min, max));
}

double ProfileReader::GetNumber(std::string_view key, double def, double min, double max) {
  return Checked(fields_.Number(key, def, min, max));
}

bool ProfileReader::GetBool(std::string_view key, bool def) {
  return Checked(fields_.Bool(key, def));
}

std::string ProfileReader::GetString(std::string_view key, std::string_view def, size_t max_bytes) {
  return Checked(fields_.String(key, def, max_bytes));
}

uint32_t ProfileReader::GetFlags(std::string_view key, uint32_t def) {
  return Checked(fields_.Bits32(key, def));
}

const nlohmann::json& ProfileReader::GetRaw(std::string_view key) {
  static const nlohmann::json kNull;
  const nlohmann::json* v = fields_.Raw(key);
  return v == nullptr ? kNull : *v;
}

ProfileReader ProfileReader::Child(std::string_view key) {
  base::JsonFields child = fields_.Child(key);
  Check();
  return ProfileReader(std::move(child), where_);
}

void ProfileReader::Finish() {
  fields_.Finish();
  Check();
}

nlohmann::json ReadProfileFile(const std::string& path, std::string* where_out) {
  const std::string where = "profile " + path;
  if (where_out != nullptr) *where_out = where;
  std::string text;
  if (auto error = base::ReadFileBounded(path, &text)) {
    throw ProfileError(where + " " + *error + " (the shipped profiles are in fixtures/profiles/)");
  }
  return ParseProfileText(text, where);
}

nlohmann::json ParseProfileText(std::string_view text, const std::string& where) {
  // The path of the value being parsed, so that a value the parser refuses
  // (1e400, beyond a double) is reported with its field's name; a key given
  // twice in one object is refused (the parser would keep the last silently,
  // e.g. a second "devices" list or "motor_count" replacing the first).
  std::string field, duplicate;
  try {
    nlohmann::json j = base::ParseJsonNotingDuplicateKeys(text, duplicate, &field, true);
    if (!duplicate.empty()) {
      throw ProfileError(where + ": field \"" + duplicate +
                         "\" is given twice in one object; only one would count: keep the one "
                         "you mean and delete the other");
    }
    if (!j.is_object()) {
      throw ProfileError(where + ": the file must be a JSON object { ... }, found " +
                         base::JsonTypeName(j));
    }
    return j;
  } catch (const nlohmann::json::parse_error& e) {
    throw ProfileError(where + ": not valid JSON at byte " + std::to_string(e.byte) +
                       "; fix the syntax there (" + e.what() + ")");
  } catch (const nlohmann::json::exception&) {
    // out_of_range 406: a number too large for a double, e.g. 1e400.
    throw ProfileError(where + ": " + (field.empty() ? "a value" : "field \"" + field + "\"") +
                       " is a number beyond the range of a double (about 1.8e308); write a "
                       "finite number within the field's range");
  }
}

}  // namespace moco::devices
