// ringtrack command-line tool: turns every error into one line on stderr and a non-zero exit.

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/version.hpp"

int main(int argc, char** argv) {
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
  try {
    app.parse(argc, argv);
    // Output that could not be written (a full disk, /dev/full) must not end in exit 0; the
    // stream reports the failure only once flushed. (Its cause, errno of whichever write failed
    // first, is gone by then.)
    std::cout.flush();
    if (!std::cout) throw ringtrack::core::Error("cannot write to standard output");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const ringtrack::core::Error& e) {
    std::cerr << "ringtrack: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "ringtrack: internal error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
