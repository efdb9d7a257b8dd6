// libFuzzer target: YAML text through the configuration reader (apply_config_yaml and
// validate_config), every line as a `--set` assignment (apply_config_override), and the text as
// a sequence folder's sequence.yaml (read_sequence_yaml). Oracle: an accepted configuration or
// sequence description prints to text that reads back to the same text.
#include <cstdint>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "ringtrack/core/config.hpp"
#include "ringtrack/io/sequence.hpp"

using namespace ringtrack;

namespace {

void config_yaml(const std::string& text) {
  core::Config config;
  fuzz::expect_errors([&] {
    core::apply_config_yaml(config, text, "fuzz.yaml");
    core::validate_config(config);
  });
  const std::string dumped = core::dump_config(config);
  fuzz::must_succeed([&] {
    core::Config again;
    core::apply_config_yaml(again, dumped, "dumped.yaml");
    fuzz::require(core::dump_config(again) == dumped, "dump_config round trip");
  });
}

void config_overrides(const std::string& text) {
  core::Config config;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    fuzz::expect_errors([&] { core::apply_config_override(config, line); });
  }
}

void sequence_yaml(const std::string& text) {
  fuzz::expect_errors([&] {
    const io::SequenceMeta meta =
        io::read_sequence_yaml(fuzz::write_scratch("sequence.yaml", text));
    (void)meta.sensor_model();
    const std::string formatted = io::format_sequence_yaml(meta);
    fuzz::must_succeed([&] {
      const auto again = io::read_sequence_yaml(fuzz::write_scratch("again.yaml", formatted));
      fuzz::require(io::format_sequence_yaml(again) == formatted, "sequence.yaml round trip");
    });
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  config_yaml(text);
  config_overrides(text);
  sequence_yaml(text);
  return 0;
}
