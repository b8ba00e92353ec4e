// Typed profile fields with errors naming the field and the fix (see profile.h).
#include "devices/profile.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "base/file_io.h"

namespace moco::devices {
namespace {

std::string TypeNameOf(const nlohmann::json& v) {
  if (v.is_number_integer()) return "an integer";
  if (v.is_number()) return "a number";
  return std::string("a ") + v.type_name();
}

}  // namespace

ProfileReader::ProfileReader(const nlohmann::json& object, std::string where, std::string path,
                             std::string doc)
    : object_(object), where_(std::move(where)), path_(std::move(path)), doc_(std::move(doc)) {
  if (!object_.is_object()) {
    throw ProfileError(where_ + ": " + (path_.empty() ? std::string("the top level") : path_) +
                       " must be a JSON object, found " + TypeNameOf(object_) +
                       "; write it as { \"field\": value, ... }");
  }
}

std::string ProfileReader::FieldName(std::string_view key) const {
  std::string name = path_;
  if (!name.empty()) name += '.';
  name += key;
  return name;
}

void ProfileReader::Fail(std::string_view key, std::string_view problem,
                         std::string_view fix) const {
  std::string msg = where_;
  msg += ": field \"";
  msg += FieldName(key);
  msg += "\" ";
  msg += problem;
  msg += "; ";
  msg += fix;
  throw ProfileError(msg);
}

bool ProfileReader::Has(std::string_view key) const { return object_.contains(key); }

const nlohmann::json* ProfileReader::Find(std::string_view key) {
  auto it = object_.find(key);
  if (it == object_.end()) return nullptr;
  if (std::find(read_.begin(), read_.end(), key) == read_.end()) read_.emplace_back(key);
  return &*it;
}

int64_t ProfileReader::GetInt(std::string_view key, int64_t def, int64_t min, int64_t max) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return def;
  const std::string range = std::to_string(min) + ".." + std::to_string(max);
  const bool integral_float = v->is_number_float() && std::isfinite(v->get<double>()) &&
                              v->get<double>() == std::floor(v->get<double>()) &&
                              std::fabs(v->get<double>()) < 9.0e15;
  if (!v->is_number_integer() && !integral_float) {
    Fail(key, "must be an integer " + range + ", found " + TypeNameOf(*v),
         "write a whole number, or remove the field to use the default " + std::to_string(def));
  }
  int64_t x = 0;
  if (integral_float) {
    x = static_cast<int64_t>(v->get<double>());
  } else if (v->is_number_unsigned() &&
             v->get<uint64_t>() > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) {
    x = std::numeric_limits<int64_t>::max();
  } else {
    x = v->get<int64_t>();
  }
  if (x < min || x > max) {
    Fail(key, "is " + v->dump() + ", outside " + range,
         "use a value in " + range + ", or remove the field to use the default " +
             std::to_string(def));
  }
  return x;
}

double ProfileReader::GetNumber(std::string_view key, double def, double min, double max) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return def;
  auto fmt = [](double d) {
    nlohmann::json j = d;
    return j.dump();
  };
  const std::string range = fmt(min) + ".." + fmt(max);
  if (!v->is_number()) {
    Fail(key, "must be a number " + range + ", found " + TypeNameOf(*v),
         "write a number, or remove the field to use the default " + fmt(def));
  }
  const double x = v->get<double>();
  if (!std::isfinite(x) || x < min || x > max) {
    Fail(key, "is " + v->dump() + ", outside " + range,
         "use a value in " + range + ", or remove the field to use the default " + fmt(def));
  }
  return x;
}

bool ProfileReader::GetBool(std::string_view key, bool def) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return def;
  if (!v->is_boolean()) {
    Fail(key, "must be true or false, found " + TypeNameOf(*v),
         std::string("write true or false, or remove the field to use the default ") +
             (def ? "true" : "false"));
  }
  return v->get<bool>();
}

std::string ProfileReader::GetString(std::string_view key, std::string_view def, size_t max_bytes) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return std::string(def);
  if (!v->is_string()) {
    Fail(key, "must be a string, found " + TypeNameOf(*v),
         "write it in double quotes, or remove the field to use the default \"" + std::string(def) +
             "\"");
  }
  std::string s = v->get<std::string>();
  if (max_bytes != 0 && s.size() > max_bytes) {
    Fail(key,
         "is " + std::to_string(s.size()) + " bytes long, more than " + std::to_string(max_bytes),
         "shorten it to at most " + std::to_string(max_bytes) + " bytes (UTF-8)");
  }
  return s;
}

uint32_t ProfileReader::GetFlags(std::string_view key, uint32_t def) {
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return def;
  if (v->is_number_unsigned() && v->get<uint64_t>() <= 0xffffffffu) {
    return static_cast<uint32_t>(v->get<uint64_t>());
  }
  if (v->is_string()) {
    const std::string s = v->get<std::string>();
    bool ok = s.size() > 2 && s.size() <= 10 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X');
    uint32_t x = 0;
    for (size_t i = 2; ok && i < s.size(); ++i) {
      const char c = s[i];
      uint32_t d = 0;
      if (c >= '0' && c <= '9') {
        d = static_cast<uint32_t>(c - '0');
      } else if (c >= 'a' && c <= 'f') {
        d = static_cast<uint32_t>(c - 'a' + 10);
      } else if (c >= 'A' && c <= 'F') {
        d = static_cast<uint32_t>(c - 'A' + 10);
      } else {
        ok = false;
      }
      x = x * 16 + d;
    }
    if (ok) return x;
  }
  Fail(key, "must be a 32-bit unsigned value, found " + v->dump(),
       "write a number 0..4294967295 or a hex string such as \"0x07ff\"");
}

const nlohmann::json& ProfileReader::GetRaw(std::string_view key) {
  static const nlohmann::json kNull;
  const nlohmann::json* v = Find(key);
  return v == nullptr ? kNull : *v;
}

ProfileReader ProfileReader::Child(std::string_view key) {
  static const nlohmann::json kEmpty = nlohmann::json::object();
  const nlohmann::json* v = Find(key);
  if (v == nullptr) return ProfileReader(kEmpty, where_, FieldName(key), doc_);
  if (!v->is_object()) {
    Fail(key, "must be an object, found " + TypeNameOf(*v),
         "write it as { \"field\": value, ... }");
  }
  return ProfileReader(*v, where_, FieldName(key), doc_);
}

void ProfileReader::Finish() const {
  for (auto it = object_.begin(); it != object_.end(); ++it) {
    if (std::find(read_.begin(), read_.end(), it.key()) == read_.end()) {
      Fail(it.key(), "is not a known field",
           "check its spelling against " + doc_ + ", or remove it");
    }
  }
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
  // The keys leading to the value being parsed, so that a value the parser
  // refuses (1e400, beyond a double) is reported with its field's name.
  std::vector<std::string> path;
  const nlohmann::json::parser_callback_t track =
      [&path](int depth, nlohmann::json::parse_event_t event, nlohmann::json& parsed) {
        // `depth` counts the containers open around the event.
        if (event == nlohmann::json::parse_event_t::key && depth >= 1 && parsed.is_string()) {
          path.resize(static_cast<size_t>(depth));
          path.back() = parsed.get<std::string>();
        } else if (event == nlohmann::json::parse_event_t::array_start && depth >= 0) {
          path.resize(static_cast<size_t>(depth) + 1);
          path.back() = "[]";
        }
        return true;
      };
  try {
    nlohmann::json j = nlohmann::json::parse(text.begin(), text.end(), track, true, true);
    if (!j.is_object()) {
      throw ProfileError(where + ": the file must be a JSON object { ... }, found " +
                         TypeNameOf(j));
    }
    return j;
  } catch (const nlohmann::json::parse_error& e) {
    throw ProfileError(where + ": not valid JSON at byte " + std::to_string(e.byte) +
                       "; fix the syntax there (" + e.what() + ")");
  } catch (const nlohmann::json::exception&) {
    // out_of_range 406: a number too large for a double, e.g. 1e400.
    std::string field;
    for (const std::string& k : path) {
      if (k == "[]" || k.empty()) {
        field += "[]";
      } else {
        field += (field.empty() ? "" : ".") + k;
      }
    }
    throw ProfileError(where + ": " + (field.empty() ? "a value" : "field \"" + field + "\"") +
                       " is a number beyond the range of a double (about 1.8e308); write a "
                       "finite number within the field's range");
  }
}

}  // namespace moco::devices
