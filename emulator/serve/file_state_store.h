// The file-backed non-volatile memory of a served device (ARCHITECTURE: a
// device keeps state through the StateStore interface; storage belongs to
// whoever serves it). docs/files.md describes the files.
#ifndef MOCO_SERVE_FILE_STATE_STORE_H_
#define MOCO_SERVE_FILE_STATE_STORE_H_

#include <filesystem>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "base/file_io.h"
#include "devices/stackshot3x/state_store.h"

namespace moco::serve {

using devices::StateLoad;
using devices::StateStore;

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

 private:
  std::string Target() const;
  std::filesystem::path path_;
  int supported_version_;
  std::optional<StateLoad> pending_;  // Open()'s load, for the next Load()
  bool unsupported_ = false;          // the file must not be replaced
  base::FileLock lock_;
  std::string error_;
};

}  // namespace moco::serve

#endif  // MOCO_SERVE_FILE_STATE_STORE_H_
