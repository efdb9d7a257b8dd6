#include "commands.hpp"

namespace ringtrack::cli {

void ConfigOptions::add_to(CLI::App& command) {
  command.add_option("--config", file, "YAML file with configuration overrides")
      ->check(CLI::ExistingFile);
  command.add_option("--set", overrides, "override one key: section.key=value (repeatable)");
}

core::Config ConfigOptions::load() const {
  core::Config config;
  if (!file.empty()) core::apply_config_file(config, file);
  for (const auto& assignment : overrides) core::apply_config_override(config, assignment);
  return config;
}

}  // namespace ringtrack::cli
