// A temporary directory for one test, removed with everything in it when the object goes out of
// scope: at the end of the test, and also when an ASSERT fails (GoogleTest returns from the test
// body, so destructors run) or an exception leaves it. Host tests only.
#pragma once

#include <stdlib.h>  // mkdtemp (POSIX)

#include <filesystem>
#include <stdexcept>
#include <string>
#include <system_error>

namespace ccmap::test {

class TempDir {
 public:
  /// Creates <system temporary directory>/<prefix>XXXXXX (mkdtemp: a fresh, unique name even
  /// when tests run in parallel). The system temporary directory honours TMPDIR. Throws
  /// std::runtime_error if the directory cannot be created.
  explicit TempDir(const std::string& prefix) {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::runtime_error("cannot create a temporary directory from " + pattern);
    }
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;  // a destructor must not throw; what cannot be removed stays
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  TempDir(TempDir&&) = delete;
  TempDir& operator=(TempDir&&) = delete;

  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::filesystem::path& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace ccmap::test
