#include <yaml-cpp/yaml.h>

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

bool ConfigOptions::sets(const std::string& key) const {
  for (const auto& assignment : overrides) {
    const auto eq = assignment.find('=');
    if (eq != std::string::npos && assignment.substr(0, eq) == key) return true;
  }
  if (file.empty()) return false;
  // load() has read the file already, so it parses; a config file nests keys in sections.
  const auto dot = key.find('.');
  const YAML::Node root = YAML::LoadFile(file);
  return dot != std::string::npos && root[key.substr(0, dot)] &&
         root[key.substr(0, dot)][key.substr(dot + 1)];
}

}  // namespace ringtrack::cli
