// Where an emulated controller keeps what its real counterpart holds in
// non-volatile memory (stackshot-protocol.txt CC_SERIAL_NUMBER, CC_NVM_ACCESS,
// CC_RAIL_CONFIG_SAVE "commits the data to NVM", CC_RAIL_CONFIG_AXIS, CC_LOG):
// an interface, an in-memory store and an atomic file store.
#ifndef MOCO_DEVICES_STACKSHOT3X_STATE_STORE_H_
#define MOCO_DEVICES_STACKSHOT3X_STATE_STORE_H_

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "base/file_io.h"

namespace moco::devices {

// The outcome of reading a store.
struct StateLoad {
  enum class Status : uint8_t {
    kEmpty,    // nothing stored yet: start from factory defaults
    kLoaded,   // `state` holds what was saved
    kCorrupt,  // something was stored but cannot be read; `message` says what
    kUnsupported,  // stored by a format version this program does not read; left
                   // untouched and never overwritten; `message` says what and the fix
  };
  Status status = Status::kEmpty;
  nlohmann::json state;  // kLoaded: an object
  std::string message;   // kCorrupt: names the file and the fault
};

// A device's non-volatile memory. Calls come from the scheduler's thread.
class StateStore {
 public:
  virtual ~StateStore() = default;
  // Reads what was saved. Never throws.
  virtual StateLoad Load() = 0;
  // Replaces the saved state with `state` (an object). Returns false when
  // it could not be stored; last_error() then says why. Never throws.
  virtual bool Save(const nlohmann::json& state) = 0;
  virtual const std::string& last_error() const = 0;
};

// A store in memory (tests, and a device run without a state file).
class MemoryStateStore final : public StateStore {
 public:
  StateLoad Load() override;
  bool Save(const nlohmann::json& state) override;
  const std::string& last_error() const override { return error_; }

  // What Save stored last (nullopt before any save).
  const std::optional<nlohmann::json>& saved() const { return saved_; }
  uint64_t save_count() const { return saves_; }
  // Makes the next Load report a corrupt store.
  void SetCorrupt(std::string message) { corrupt_ = std::move(message); }

 private:
  std::optional<nlohmann::json> saved_;
  std::optional<std::string> corrupt_;
  uint64_t saves_ = 0;
  std::string error_;
};

// A JSON file, written by base::WriteFile: a regular file is replaced through
// an exclusive temporary file, flushed to the disk and renamed, so a crash
// leaves either the old or the new file; a symlink is followed and its final
// target replaced (the link stays); a character device or FIFO (--state
// /dev/null: keep nothing) is written in place and reads as empty.
// Load of a file that is not a JSON object moves it aside to the first free
// "<target>.corrupt", "<target>.corrupt.1", ... (never replacing an older
// copy) and reports kCorrupt with a message naming the file and the copy; the
// next Load then finds nothing (kEmpty). A "version" other than
// `supported_version` is kUnsupported: the file is left as it is and Save
// refuses to replace it.
class FileStateStore final : public StateStore {
 public:
  explicit FileStateStore(std::filesystem::path path, int supported_version = 1);

  // What serving a device does first: takes an exclusive lock on
  // "<target>.lock" for the store's lifetime (none for a device or FIFO) and
  // loads the file; `first` receives that load, which the next Load() returns
  // again (so the device sees it too). Returns a message naming the file and
  // the fix when it cannot be used: a directory or special file, locked by
  // another process, or an unsupported version.
  std::optional<std::string> Open(StateLoad* first);

  StateLoad Load() override;
  bool Save(const nlohmann::json& state) override;
  const std::string& last_error() const override { return error_; }

  const std::filesystem::path& path() const { return path_; }
  // Where the first corrupt copy goes ("<target>.corrupt").
  std::filesystem::path CorruptPath() const;
  // The lock file Open() holds ("<target>.lock").
  std::filesystem::path LockPath() const;

 private:
  std::string Target() const;
  std::filesystem::path path_;
  int supported_version_;
  std::optional<StateLoad> pending_;  // Open()'s load, for the next Load()
  bool unsupported_ = false;          // the file must not be replaced
  base::FileLock lock_;
  std::string error_;
};

}  // namespace moco::devices

#endif  // MOCO_DEVICES_STACKSHOT3X_STATE_STORE_H_
