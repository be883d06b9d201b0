#pragma once
/// Writing outputs so that an interrupted or failed run never leaves a partial file that looks
/// complete: write to a temporary name in the same folder, then rename over the final name.
#include <functional>
#include <string>

namespace tdf {

/// Calls `write(temporary_path)`, then renames the temporary file to `path`. If `write`
/// throws, the temporary file is removed and the exception propagates; `path` is untouched.
/// The temporary name keeps the extension (`name.tmp123.exr`) so format-by-extension writers
/// work. Creates missing parent folders.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write);

/// Throws tdf::Error ("cannot write '<path>': it is a folder, not a file name") when `path` names
/// a folder: commands call it before long work so the error comes first.
void check_output_file_name(const std::string& path);

/// Writes `text` to `path` atomically.
void write_text_atomically(const std::string& path, const std::string& text);

/// Reads a whole file; throws tdf::Error naming the file when it cannot.
std::string read_text_file(const std::string& path);

/// Creates `folder` and its parents; throws tdf::Error when that fails.
void ensure_folder(const std::string& folder);

}  // namespace tdf
