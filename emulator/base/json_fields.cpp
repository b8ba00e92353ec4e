// Typed JSON fields with problems naming the field and the fix (see json_fields.h).
#include "base/json_fields.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "base/format.h"

namespace moco::base {
namespace {

using nlohmann::json;
using Kind = FieldProblem::Kind;

const char kObjectFix[] = "write it as { \"field\": value, ... }";

// A value as written, cut to about 40 characters.
std::string Shown(const json& v) {
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 40) s = s.substr(0, 37) + "...";
  return s;
}

std::string Num(double d) { return json(d).dump(); }

std::string OrDefault(Presence presence, const std::string& def) {
  return presence == kRequired ? "" : ", or remove the field to use the default " + def;
}

std::string InUnit(std::string_view unit) { return unit.empty() ? "" : " in " + std::string(unit); }

}  // namespace

std::string JsonTypeName(const json& v) {
  if (v.is_number_integer()) return "an integer";
  if (v.is_number()) return "a number";
  return std::string("a ") + v.type_name();
}

std::string FieldProblem::Message() const {
  if (kind == Kind::kNotObject) {
    return (field.empty() ? std::string("the top level") : field) + " " + problem + "; " + fix;
  }
  return "field \"" + field + "\" " + problem + "; " + fix;
}

JsonFields::JsonFields(const json& object, std::string path, std::string doc)
    : JsonFields(&object, std::move(path), std::move(doc),
                 std::make_shared<std::optional<FieldProblem>>()) {}

JsonFields::JsonFields(const json* object, std::string path, std::string doc,
                       std::shared_ptr<std::optional<FieldProblem>> problem)
    : object_(object), path_(std::move(path)), doc_(std::move(doc)), problem_(std::move(problem)) {
  if (object_ != nullptr && !object_->is_object()) {
    FieldProblem p;
    p.kind = Kind::kNotObject;
    p.field = path_;
    p.expected = "an object";
    p.found = JsonTypeName(*object_);
    p.problem = "must be a JSON object, found " + p.found;
    p.fix = kObjectFix;
    Keep(std::move(p));
    object_ = nullptr;
  }
}

std::string JsonFields::FieldName(std::string_view key) const {
  if (key.empty()) return path_;
  std::string name = path_;
  if (!name.empty()) name += '.';
  name += key;
  return name;
}

bool JsonFields::Has(std::string_view key) const {
  return object_ != nullptr && object_->contains(key);
}

const json* JsonFields::Find(std::string_view key) {
  if (std::find(read_.begin(), read_.end(), key) == read_.end()) read_.emplace_back(key);
  if (object_ == nullptr) return nullptr;
  auto it = object_->find(key);
  return it == object_->end() ? nullptr : &*it;
}

std::optional<FieldProblem> JsonFields::TakeProblem() {
  std::optional<FieldProblem> p = std::move(*problem_);
  problem_->reset();
  return p;
}

void JsonFields::Keep(FieldProblem p) {
  if (!problem_->has_value()) *problem_ = std::move(p);
}

void JsonFields::Refuse(Kind kind, std::string_view key, const json* v, std::string expected,
                        std::string problem, std::string fix) {
  if (failed()) return;
  FieldProblem p;
  p.kind = kind;
  p.field = FieldName(key);
  p.expected = std::move(expected);
  if (v != nullptr) {
    p.found = JsonTypeName(*v);
    p.value = Shown(*v);
  }
  p.problem = std::move(problem);
  p.fix = std::move(fix);
  Keep(std::move(p));
}

void JsonFields::Missing(std::string_view key, const std::string& expected) {
  Refuse(Kind::kMissing, key, nullptr, expected, "is missing", "add " + expected);
}

void JsonFields::Fail(std::string_view key, std::string_view problem, std::string_view fix) {
  Refuse(Kind::kOther, key, nullptr, "", std::string(problem), std::string(fix));
}

int64_t JsonFields::Int(std::string_view key, int64_t def, int64_t min, int64_t max,
                        Presence presence) {
  const json* v = Find(key);
  const std::string range = std::to_string(min) + ".." + std::to_string(max);
  const std::string expected = "an integer " + range;
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, expected);
    return def;
  }
  const bool integral_float = v->is_number_float() && std::isfinite(v->get<double>()) &&
                              v->get<double>() == std::floor(v->get<double>()) &&
                              std::fabs(v->get<double>()) < 9.0e15;
  if (!v->is_number_integer() && !integral_float) {
    Refuse(Kind::kType, key, v, expected, "must be " + expected + ", found " + JsonTypeName(*v),
           "write a whole number" + OrDefault(presence, std::to_string(def)));
    return def;
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
    Refuse(Kind::kRange, key, v, expected, "is " + Shown(*v) + ", outside " + range,
           "use a value in " + range + OrDefault(presence, std::to_string(def)));
    return def;
  }
  return x;
}

double JsonFields::Number(std::string_view key, double def, double min, double max,
                          Presence presence, std::string_view unit) {
  const json* v = Find(key);
  const std::string range = Num(min) + ".." + Num(max);
  const std::string expected = "a number " + range;
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, expected + InUnit(unit));
    return def;
  }
  if (!v->is_number()) {
    Refuse(Kind::kType, key, v, expected, "must be " + expected + ", found " + JsonTypeName(*v),
           "write a number" + InUnit(unit) + OrDefault(presence, Num(def)));
    return def;
  }
  const double x = v->get<double>();
  if (!std::isfinite(x) || x < min || x > max) {
    Refuse(Kind::kRange, key, v, expected, "is " + Shown(*v) + ", outside " + range,
           "use a value in " + range + OrDefault(presence, Num(def)));
    return def;
  }
  return x;
}

bool JsonFields::Bool(std::string_view key, bool def, Presence presence) {
  const json* v = Find(key);
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, "true or false");
    return def;
  }
  if (!v->is_boolean()) {
    Refuse(Kind::kType, key, v, "true or false", "must be true or false, found " + JsonTypeName(*v),
           "write true or false" + OrDefault(presence, def ? "true" : "false"));
    return def;
  }
  return v->get<bool>();
}

std::string JsonFields::String(std::string_view key, std::string_view def, size_t max_bytes,
                               Presence presence) {
  const json* v = Find(key);
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, "a string");
    return std::string(def);
  }
  if (!v->is_string()) {
    Refuse(Kind::kType, key, v, "a string", "must be a string, found " + JsonTypeName(*v),
           "write it in double quotes" + OrDefault(presence, "\"" + std::string(def) + "\""));
    return std::string(def);
  }
  std::string s = v->get<std::string>();
  if (max_bytes != 0 && s.size() > max_bytes) {
    Refuse(Kind::kRange, key, v, "a string",
           "is " + std::to_string(s.size()) + " bytes long, more than " + std::to_string(max_bytes),
           "shorten it to at most " + std::to_string(max_bytes) + " bytes (UTF-8)");
    return std::string(def);
  }
  return s;
}

uint32_t JsonFields::Bits32(std::string_view key, uint32_t def, Presence presence) {
  const json* v = Find(key);
  const std::string expected = "a 32-bit unsigned value";
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, expected);
    return def;
  }
  if (v->is_number_unsigned() && v->get<uint64_t>() <= 0xffffffffu) {
    return static_cast<uint32_t>(v->get<uint64_t>());
  }
  if (v->is_string()) {
    if (const std::optional<uint32_t> x = ParseHex32(v->get_ref<const std::string&>())) return *x;
  }
  Refuse(Kind::kType, key, v, expected, "must be " + expected + ", found " + Shown(*v),
         "write a number 0..4294967295 or a hex string such as \"0x07ff\"");
  return def;
}

std::optional<size_t> JsonFields::Choice(std::string_view key,
                                         std::span<const std::string_view> choices,
                                         Presence presence) {
  const json* v = Find(key);
  std::string listed;
  for (std::string_view c : choices) {
    if (!listed.empty()) listed += " or ";
    listed += "\"" + std::string(c) + "\"";
  }
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, listed);
    return std::nullopt;
  }
  if (v->is_string()) {
    const std::string& s = v->get_ref<const std::string&>();
    for (size_t i = 0; i < choices.size(); ++i) {
      if (s == choices[i]) return i;
    }
  }
  Refuse(Kind::kType, key, v, listed,
         "must be " + listed + ", found " + JsonTypeName(*v) + " " + Shown(*v), "write " + listed);
  return std::nullopt;
}

std::vector<double> JsonFields::Numbers(std::string_view key, double min, double max,
                                        size_t min_count, size_t max_count, Presence presence) {
  const json* v = Find(key);
  const std::string range = Num(min) + ".." + Num(max);
  const std::string count = min_count == max_count
                                ? std::to_string(min_count)
                                : std::to_string(min_count) + ".." + std::to_string(max_count);
  const std::string expected = "an array of " + count + " numbers " + range;
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, expected);
    return {};
  }
  if (!v->is_array() || v->size() < min_count || v->size() > max_count) {
    const std::string found =
        v->is_array() ? "an array of " + std::to_string(v->size()) : JsonTypeName(*v);
    Refuse(Kind::kType, key, v, expected, "must be " + expected + ", found " + found,
           "write [n, n, ...] with " + count + " numbers in " + range);
    return {};
  }
  std::vector<double> out;
  for (size_t i = 0; i < v->size(); ++i) {
    const json& e = (*v)[i];
    const std::string element = std::string(key) + "[" + std::to_string(i) + "]";
    if (!e.is_number()) {
      Refuse(Kind::kType, element, &e, "a number " + range,
             "must be a number " + range + ", found " + JsonTypeName(e), "use numbers in " + range);
      return {};
    }
    if (!std::isfinite(e.get<double>()) || e.get<double>() < min || e.get<double>() > max) {
      Refuse(Kind::kRange, element, &e, "a number " + range,
             "is " + Shown(e) + ", outside " + range, "use numbers in " + range);
      return {};
    }
    out.push_back(e.get<double>());
  }
  return out;
}

const json* JsonFields::Raw(std::string_view key) { return Find(key); }

const json* JsonFields::Array(std::string_view key, Presence presence) {
  const json* v = Find(key);
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, "an array [ ... ]");
    return nullptr;
  }
  if (!v->is_array()) {
    Refuse(Kind::kType, key, v, "an array", "must be an array, found " + JsonTypeName(*v),
           "write it as [ ... ]");
    return nullptr;
  }
  return v;
}

JsonFields JsonFields::Child(std::string_view key, Presence presence) {
  const json* v = Find(key);
  if (v == nullptr) {
    if (presence == kRequired && object_ != nullptr) Missing(key, "an object { ... }");
  } else if (!v->is_object()) {
    Refuse(Kind::kType, key, v, "an object", "must be an object, found " + JsonTypeName(*v),
           kObjectFix);
    v = nullptr;
  }
  return JsonFields(v, FieldName(key), doc_, problem_);
}

JsonFields JsonFields::Item(std::string_view key, size_t index) {
  const json* array = Find(key);
  return JsonFields(&array->at(index), FieldName(key) + "[" + std::to_string(index) + "]", doc_,
                    problem_);
}

void JsonFields::Finish() {
  if (object_ == nullptr || failed()) return;
  for (auto it = object_->begin(); it != object_->end(); ++it) {
    if (std::find(read_.begin(), read_.end(), it.key()) != read_.end()) continue;
    std::string fix;
    if (!doc_.empty()) {
      fix = "check its spelling against " + doc_ + ", or remove it";
    } else {
      std::vector<std::string> known = read_;
      std::sort(known.begin(), known.end());
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      fix = "check its spelling (known here: " + list + "), or remove it";
    }
    Refuse(Kind::kUnknown, it.key(), nullptr, "", "is not a known field", fix);
    return;
  }
}

namespace {

std::string PathText(const std::vector<std::string>& path) {
  std::string out;
  for (const std::string& k : path) {
    if (k == "[]" || k.empty()) {
      out += "[]";
    } else {
      out += (out.empty() ? "" : ".") + k;
    }
  }
  return out;
}

}  // namespace

nlohmann::json ParseJsonNotingDuplicateKeys(std::string_view text, std::string& duplicate,
                                            std::string* at, bool ignore_comments) {
  using Event = nlohmann::json::parse_event_t;
  duplicate.clear();
  std::vector<std::string> path;               // the keys leading to the value parsed
  std::vector<std::vector<std::string>> keys;  // the keys of each object open
  const nlohmann::json::parser_callback_t note = [&](int depth, Event event,
                                                     nlohmann::json& parsed) {
    // `depth` counts the containers open around the event.
    if (event == Event::object_start) {
      keys.emplace_back();
    } else if (event == Event::object_end) {
      if (!keys.empty()) keys.pop_back();
    } else if (event == Event::key && depth >= 1 && parsed.is_string()) {
      path.resize(static_cast<size_t>(depth));
      path.back() = parsed.get<std::string>();
      if (!keys.empty()) {
        std::vector<std::string>& seen = keys.back();
        if (std::find(seen.begin(), seen.end(), path.back()) != seen.end()) {
          if (duplicate.empty()) duplicate = PathText(path);
        } else {
          seen.push_back(path.back());
        }
      }
    } else if (event == Event::array_start && depth >= 0) {
      path.resize(static_cast<size_t>(depth) + 1);
      path.back() = "[]";
    }
    if (at != nullptr) *at = PathText(path);
    return true;
  };
  return nlohmann::json::parse(text.begin(), text.end(), note, /*allow_exceptions=*/true,
                               ignore_comments);
}

}  // namespace moco::base
