// Where the real terrain data lives (the team's ../shared/data; absent in a user's clone).
#pragma once

#include <string>

namespace ccmap::sim {

/// The data directory: `flag_value` if non-empty, else $CCMAP_DATA_DIR if set and non-empty,
/// else the build-time default <source dir>/../shared/data.
std::string resolve_data_dir(const std::string& flag_value = "");

/// Path of the HiRISE Mars DTM inside a data directory.
std::string mars_dtm_path(const std::string& data_dir);

/// True if `path` is a readable file; otherwise false and a sentence saying why in *why
/// (what was looked for, and how to point at the data: --data DIR or CCMAP_DATA_DIR).
bool data_file_available(const std::string& path, std::string* why);

}  // namespace ccmap::sim
