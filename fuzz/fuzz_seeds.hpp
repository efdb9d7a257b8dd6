#pragma once
// Seed inputs of the libFuzzer targets, generated from the test suite's independent writers
// (tests/support: packet encoders, ROS bag writers) and the repository's own files (config/), so
// that every fuzzer starts from valid inputs of its format instead of from nothing.

#include <filesystem>

namespace ringtrack::fuzz {

/// Writes a rosbag2 folder (`folder`/bag2_0.db3 and metadata.yaml) with one VelodyneScan topic of
/// two small messages.
void write_small_rosbag2(const std::filesystem::path& folder);

/// Writes the seeds of every target into `out`/<target>/; config/ files come from `source_dir`.
void write_all_seeds(const std::filesystem::path& out, const std::filesystem::path& source_dir);

}  // namespace ringtrack::fuzz
