// Non-volatile state stores (see state_store.h).
#include "devices/stackshot3x/state_store.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

// fsync: the one POSIX call the atomic write needs (std::fstream cannot
// force data to the disk before the rename).
#include <unistd.h>

namespace moco::devices {

StateLoad MemoryStateStore::Load() {
  StateLoad out;
  if (corrupt_) {
    out.status = StateLoad::Status::kCorrupt;
    out.message = *corrupt_;
    corrupt_.reset();
    return out;
  }
  if (saved_) {
    out.status = StateLoad::Status::kLoaded;
    out.state = *saved_;
  }
  return out;
}

bool MemoryStateStore::Save(const nlohmann::json& state) {
  saved_ = state;
  ++saves_;
  return true;
}

FileStateStore::FileStateStore(std::filesystem::path path) : path_(std::move(path)) {}

std::filesystem::path FileStateStore::PartialPath() const {
  std::filesystem::path p = path_;
  p += ".partial";
  return p;
}

std::filesystem::path FileStateStore::CorruptPath() const {
  std::filesystem::path p = path_;
  p += ".corrupt";
  return p;
}

StateLoad FileStateStore::Load() {
  StateLoad out;
  std::error_code ec;
  if (!std::filesystem::exists(path_, ec)) return out;  // kEmpty
  std::string problem;
  {
    std::ifstream in(path_, std::ios::binary);
    if (!in) {
      problem = "cannot be opened for reading";
    } else {
      std::ostringstream text;
      text << in.rdbuf();
      nlohmann::json j = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
      if (j.is_discarded()) {
        problem = "is not valid JSON";
      } else if (!j.is_object()) {
        problem = "does not hold a JSON object";
      } else {
        out.status = StateLoad::Status::kLoaded;
        out.state = std::move(j);
        return out;
      }
    }
  }
  out.status = StateLoad::Status::kCorrupt;
  out.message = "state file " + path_.string() + " " + problem;
  std::filesystem::rename(path_, CorruptPath(), ec);
  if (ec) {
    out.message += "; it could not be moved aside (" + ec.message() + ")";
  } else {
    out.message +=
        "; kept aside as " + CorruptPath().filename().string() + ", starting from defaults";
  }
  return out;
}

bool FileStateStore::Save(const nlohmann::json& state) {
  const std::filesystem::path partial = PartialPath();
  const std::string text = state.dump(2) + "\n";
  std::FILE* f = std::fopen(partial.c_str(), "wb");
  if (f == nullptr) {
    error_ = "cannot write " + partial.string() + ": " + std::strerror(errno);
    return false;
  }
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size() &&
                       std::fflush(f) == 0 && ::fsync(::fileno(f)) == 0;
  const int write_errno = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed) {
    error_ = "cannot write " + partial.string() + ": " + std::strerror(write_errno);
    std::error_code ignored;
    std::filesystem::remove(partial, ignored);
    return false;
  }
  std::error_code ec;
  std::filesystem::rename(partial, path_, ec);
  if (ec) {
    error_ = "cannot rename " + partial.string() + " to " + path_.string() + ": " + ec.message();
    return false;
  }
  error_.clear();
  return true;
}

}  // namespace moco::devices
