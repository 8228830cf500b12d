#include "sim/data_dir.hpp"

#include <cstdlib>
#include <fstream>

#ifndef CCMAP_DEFAULT_DATA_DIR
#define CCMAP_DEFAULT_DATA_DIR "../shared/data"
#endif

namespace ccmap::sim {

std::string resolve_data_dir(const std::string& flag_value) {
  if (!flag_value.empty()) return flag_value;
  const char* env = std::getenv("CCMAP_DATA_DIR");
  if (env != nullptr && env[0] != '\0') return env;
  return CCMAP_DEFAULT_DATA_DIR;
}

std::string mars_dtm_path(const std::string& data_dir) { return data_dir + "/hirise_mars_dtm/mars_dtm_1.01m.asc"; }

bool data_file_available(const std::string& path, std::string* why) {
  std::ifstream in(path);
  if (in.good()) return true;
  if (why != nullptr) {
    *why = "real-data file " + path +
           " is not available (the shared data set is not part of the repository; point at it with "
           "--data DIR or the CCMAP_DATA_DIR environment variable)";
  }
  return false;
}

}  // namespace ccmap::sim
