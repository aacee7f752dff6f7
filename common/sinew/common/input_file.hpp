#pragma once
// The check every reader makes before opening an input file: it must be a regular file (or a
// link to one). A folder, a FIFO nobody writes to, a socket or a device such as /dev/zero would
// otherwise fail late with a vague message, block the reader forever (a FIFO) or feed it without
// end (/dev/zero); a missing or unreadable file gets the system's reason.
//
//   require_regular_file("scene.yaml", "scene file");
//   -> IoError "scene.yaml: the scene file is a FIFO (named pipe), not a regular file"
#include <filesystem>
#include <string>

namespace sinew {

// Throws IoError naming `path` when it does not exist, cannot be examined or is not a regular
// file; `what` names the file's role in the message ("scene file", "model file").
void require_regular_file(const std::filesystem::path& path, const std::string& what);

}  // namespace sinew
