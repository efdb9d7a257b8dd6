#include "data_dirs.hpp"

#include <system_error>

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;

// The running binary. argv[0] may be relative, a PATH lookup or a symlink; the kernel's link
// names the file itself.
fs::path own_executable() {
  std::error_code ec;
  fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe;
}

// True for the binary the build tree made (the same file, not merely the same name), which
// reads the source tree. Any other copy, the installed one above all, reads only what was
// installed beside it: a stale source tree on the same machine must not leak into an install.
bool from_build_tree() {
  std::error_code ec;
  return fs::equivalent(own_executable(), RINGTRACK_BUILD_TREE_EXE, ec);
}

// <prefix>/bin/ringtrack -> <prefix>/<relative>; relative comes from GNUInstallDirs at
// configure time, so `cmake --install --prefix` anywhere keeps it right.
fs::path beside_install(const char* relative) {
  return (own_executable().parent_path() / relative).lexically_normal();
}

}  // namespace

fs::path scripts_dir() {
  return from_build_tree() ? fs::path(RINGTRACK_SOURCE_SCRIPTS_DIR)
                           : beside_install(RINGTRACK_INSTALLED_DATA_DIR) / "scripts";
}

fs::path config_dir() {
  return from_build_tree() ? fs::path(RINGTRACK_SOURCE_CONFIG_DIR)
                           : beside_install(RINGTRACK_INSTALLED_DATA_DIR) / "config";
}

fs::path python_dir() {
  return from_build_tree() ? fs::path(RINGTRACK_BUILD_PYTHON_DIR)
                           : beside_install(RINGTRACK_INSTALLED_PYTHON_DIR);
}

}  // namespace ringtrack::cli
