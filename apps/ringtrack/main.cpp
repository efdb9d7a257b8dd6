// ringtrack command-line tool: turns every error into one line on stderr and a non-zero exit.

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/version.hpp"

namespace {

int run(int argc, char** argv) {
  CLI::App app{"ringtrack: detect and track small objects in spinning-LiDAR scans"};
  app.set_version_flag("--version", std::string("ringtrack ") + ringtrack::kVersion);
  app.require_subcommand(1);
  ringtrack::cli::register_dump_config(app);
  ringtrack::cli::register_demo(app);
  ringtrack::cli::register_run(app);
  ringtrack::cli::register_eval(app);
  ringtrack::cli::register_eval_trajectory(app);
  ringtrack::cli::register_simulate(app);
  ringtrack::cli::register_convert(app);
  ringtrack::cli::register_benchmark(app);
  ringtrack::cli::register_sensors(app);
  ringtrack::cli::register_tune(app);
  ringtrack::cli::set_command_line(argc, argv);
  try {
    app.parse(argc, argv);
    // Output that could not be written (a full disk, /dev/full) must not end in exit 0; the
    // stream reports the failure only once flushed. (Its cause, errno of whichever write failed
    // first, is gone by then.)
    ringtrack::cli::check_stdout();
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // --help and --version print here and return 0
    if (code == 0) {
      try {
        ringtrack::cli::check_stdout();
      } catch (const ringtrack::core::Error& error) {
        std::cerr << "ringtrack: error: " << error.what() << "\n";
        return 1;
      }
    }
    return code;
  } catch (const ringtrack::core::Error& e) {
    std::cerr << "ringtrack: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "ringtrack: internal error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}

}  // namespace

// What run lets escape (the command line set up before its try: CLI11's option setup, an
// allocation) is an internal error too, never std::terminate.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "ringtrack: internal error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "ringtrack: internal error: an exception of unknown type\n";
  }
  return 2;
}
