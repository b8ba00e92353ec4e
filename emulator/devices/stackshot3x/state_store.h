// Where an emulated controller keeps what its real counterpart holds in
// non-volatile memory (stackshot-protocol.txt CC_SERIAL_NUMBER, CC_NVM_ACCESS,
// CC_RAIL_CONFIG_SAVE "commits the data to NVM", CC_RAIL_CONFIG_AXIS, CC_LOG):
// the interface and an in-memory store. The file store belongs to whoever
// serves the device (serve/file_state_store.h): a device opens no file.
#ifndef MOCO_DEVICES_STACKSHOT3X_STATE_STORE_H_
#define MOCO_DEVICES_STACKSHOT3X_STATE_STORE_H_

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

namespace moco::devices {

// The outcome of reading a store.
struct StateLoad {
  enum class Status : uint8_t {
    kEmpty,        // nothing stored yet: start from factory defaults
    kLoaded,       // `state` holds what was saved
    kCorrupt,      // something was stored but cannot be read; `message` says what
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

}  // namespace moco::devices

#endif  // MOCO_DEVICES_STACKSHOT3X_STATE_STORE_H_
