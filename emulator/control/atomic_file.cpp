// Whole-file replacement through a temporary file and rename (see atomic_file.h).
#include "control/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace moco::control {

std::optional<std::string> WriteFileAtomically(const std::string& path, std::string_view text) {
  const std::string partial = path + ".partial-" + std::to_string(::getpid());
  std::FILE* f = std::fopen(partial.c_str(), "wb");
  if (f == nullptr) {
    return "cannot write " + path + ": " + std::strerror(errno) + " (creating " + partial + ")";
  }
  int error = 0;
  if (!text.empty() && std::fwrite(text.data(), 1, text.size(), f) != text.size()) error = errno;
  if (std::fclose(f) != 0 && error == 0) error = errno;
  if (error != 0) {
    std::remove(partial.c_str());
    return "cannot write " + path + ": " + std::strerror(error) + " (writing " + partial + ")";
  }
  if (std::rename(partial.c_str(), path.c_str()) != 0) {
    error = errno;
    std::remove(partial.c_str());
    return "cannot write " + path + ": " + std::strerror(error) + " (renaming " + partial +
           " to it)";
  }
  return std::nullopt;
}

}  // namespace moco::control
