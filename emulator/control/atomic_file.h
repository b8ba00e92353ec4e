// Whole-file replacement for generated documents (reports, plots): the text
// goes to a temporary file beside the target, which is then renamed over it,
// so readers see either the old file or the new one, never a part.
#ifndef MOCO_CONTROL_ATOMIC_FILE_H_
#define MOCO_CONTROL_ATOMIC_FILE_H_

#include <optional>
#include <string>
#include <string_view>

namespace moco::control {

// Writes `text` to "<path>.partial-<pid>" in the same directory and renames it
// to `path` (POSIX rename replaces an existing file in one step). Returns
// nullopt on success; otherwise a message naming `path` and the system's
// reason (strerror), and then no temporary file is left behind and a previous
// file at `path` is untouched. No fsync: atomic against concurrent readers and
// a failing write, not against a power cut.
std::optional<std::string> WriteFileAtomically(const std::string& path, std::string_view text);

}  // namespace moco::control

#endif  // MOCO_CONTROL_ATOMIC_FILE_H_
