#include <iostream>
#include <memory>

#include "commands.hpp"

namespace ringtrack::cli {

void register_dump_config(CLI::App& app) {
  auto* cmd = app.add_subcommand("dump-config",
                                 "print the effective configuration: every key, value and meaning");
  auto options = std::make_shared<ConfigOptions>();
  options->add_to(*cmd);
  cmd->callback([options] { std::cout << core::dump_config(options->load()); });
}

}  // namespace ringtrack::cli
