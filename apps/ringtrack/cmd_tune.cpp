// `ringtrack tune`: runs the Python tuner (python/ringtrack/tune.py, Optuna from Debian) with
// every argument after `tune`, so that the help, errors and exit codes are the tuner's own.

#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "data_dirs.hpp"

namespace ringtrack::cli {
namespace {

[[noreturn]] void exec_tuner(const std::vector<std::string>& args) {
  const char* python = "/usr/bin/python3";
  // This binary's own package first (the build tree's, or the one installed with it), so that
  // the tuner and this binary are the same version.
  std::string path = python_dir().string();
  if (const char* old = std::getenv("PYTHONPATH"); old != nullptr && *old != '\0') {
    path.push_back(':');
    path.append(old);
  }
  setenv("PYTHONPATH", path.c_str(), 1);
  std::vector<std::string> words = {python, "-m", "ringtrack.tune"};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  execv(python, argv.data());
  std::cerr << "ringtrack tune: cannot start " << python << ": " << std::strerror(errno)
            << " (apt-get install python3 python3-optuna; scripts/bootstrap)\n";
  std::exit(1);
}

}  // namespace

void register_tune(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "tune",
      "tune the parameters on simulated scenarios with Optuna's TPE (leave-one-out, workers, "
      "PostgreSQL studies; `ringtrack tune --help`, docs/tuning.md)");
  cmd->prefix_command();  // everything after `tune` goes to the tuner, --help included
  cmd->set_help_flag();
  cmd->callback([cmd] { exec_tuner(cmd->remaining()); });
}

}  // namespace ringtrack::cli
