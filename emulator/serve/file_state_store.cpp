// The file-backed non-volatile memory of a served device.
#include "serve/file_state_store.h"

#include <utility>

namespace moco::serve {

FileStateStore::FileStateStore(std::filesystem::path path, int supported_version)
    : path_(std::move(path)), supported_version_(supported_version) {}

std::string FileStateStore::Target() const {
  base::OutputTarget t;
  return base::ResolveOutput(path_.string(), &t) ? path_.string() : t.path;
}

std::filesystem::path FileStateStore::CorruptPath() const { return Target() + ".corrupt"; }

std::optional<std::string> FileStateStore::Open(StateLoad* first) {
  const std::string where = "state file " + path_.string();
  base::OutputTarget target;
  if (auto error = base::ResolveOutput(path_.string(), &target)) {
    return "state file " + *error + "; or give another file with --state PATH";
  }
  if (target.kind == base::PathKind::kRegular || target.kind == base::PathKind::kMissing) {
    if (lock_.Acquire(target.path + ".lock")) {
      return where + " is in use by another running mocosim (it holds " + target.path +
             ".lock); give this device its own file with --state PATH (\"state\" in a run file)";
    }
  }
  pending_.reset();
  StateLoad load = Load();
  if (load.status == StateLoad::Status::kUnsupported) return load.message;
  *first = load;
  pending_ = std::move(load);
  return std::nullopt;
}

StateLoad FileStateStore::Load() {
  if (pending_) {
    StateLoad out = std::move(*pending_);
    pending_.reset();
    return out;
  }
  StateLoad out;
  const std::string where = "state file " + path_.string();
  base::OutputTarget target;
  if (auto error = base::ResolveOutput(path_.string(), &target)) {
    out.status = StateLoad::Status::kCorrupt;
    out.message = "state file " + *error;
    return out;
  }
  // Nothing stored yet; a device or FIFO (/dev/null: keep nothing) holds no state.
  if (target.kind != base::PathKind::kRegular) return out;
  std::string text;
  if (auto error = base::ReadFileBounded(target.path, &text)) {
    // Unreadable is not corrupt: the file is left where it is.
    out.status = StateLoad::Status::kCorrupt;
    out.message = where + " " + *error;
    return out;
  }
  std::string problem;
  nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    problem = text.empty() ? "is empty" : "is not valid JSON (cut short?)";
  } else if (!j.is_object()) {
    problem = "does not hold a JSON object";
  } else if (const auto v = j.find("version");
             v != j.end() && !(v->is_number_integer() && v->get<int64_t>() == supported_version_)) {
    unsupported_ = true;
    out.status = StateLoad::Status::kUnsupported;
    out.message = where + " has \"version\": " + v->dump() + "; this mocosim reads version " +
                  std::to_string(supported_version_) +
                  " (was it written by a newer one?). It is left untouched: give another file "
                  "with --state PATH, or move it away to start from defaults";
    return out;
  } else {
    unsupported_ = false;
    out.status = StateLoad::Status::kLoaded;
    out.state = std::move(j);
    return out;
  }
  out.status = StateLoad::Status::kCorrupt;
  out.message = where + " " + problem;
  std::string moved_to;
  if (auto error = base::MoveAsideNumbered(target.path, ".corrupt", &moved_to)) {
    out.message += "; it could not be kept aside (" + *error + ")";
  } else {
    out.message += "; kept as " + moved_to + ", starting from defaults";
  }
  return out;
}

bool FileStateStore::Save(const nlohmann::json& state) {
  if (unsupported_) {
    error_ = "state file " + path_.string() +
             " has a version this mocosim does not read; it is not replaced";
    return false;
  }
  if (auto error = base::WriteFileAtomically(path_.string(), state.dump(2) + "\n",
                                             /*sync=*/true)) {
    error_ = *error;
    return false;
  }
  error_.clear();
  return true;
}

}  // namespace moco::serve
