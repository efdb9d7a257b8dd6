#include "commands.hpp"

namespace ringtrack::cli {
void register_demo(CLI::App&) {}
}  // namespace ringtrack::cli
