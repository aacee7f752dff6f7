#pragma once
// Writing an export file without ever leaving a half-written one under its final name: the bytes
// go to "<path>.tmp-<pid>" (same folder, so the rename stays on one file system), which is closed
// and renamed onto `path` only once complete; on any error the temporary file is removed and
// `path` is left as it was.
#include <string>
#include <string_view>

namespace sinew::postprocess {

// Writes `bytes` to `path` as above. Throws IoError naming `path` when the temporary file cannot
// be created, written (disk full), closed or renamed.
void write_file_atomically(const std::string& path, std::string_view bytes);

}  // namespace sinew::postprocess
