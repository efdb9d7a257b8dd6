#pragma once
/// Test support: a fresh temporary folder per test, removed with its contents afterwards.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <system_error>

namespace ringtrack::test {

/// A fresh folder under the system temp dir named after the running test (and the process, so
/// parallel ctest runs do not collide), removed with its contents on destruction.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = "ringtrack_" + std::to_string(::getpid()) + "_" + info->test_suite_name() +
                       "_" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');  // parameterized tests: Prefix/Suite.Name/0
    path_ = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  /// The folder.
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  /// A path inside the folder.
  [[nodiscard]] std::filesystem::path operator/(const std::string& name) const {
    return path_ / name;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace ringtrack::test
