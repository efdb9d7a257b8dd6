#pragma once
/// Small, locale-independent text helpers shared by the io readers and writers.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace ringtrack::io {

/// Splits a line at spaces, tabs and (when commas is true) commas; empty tokens are dropped.
std::vector<std::string_view> split_tokens(std::string_view line, bool commas = false);
/// Parses a whole token as a double ("nan" and "inf" included); nullopt unless all of it parses.
std::optional<double> parse_double(std::string_view token);
/// Parses a whole token as a signed 64-bit integer.
std::optional<std::int64_t> parse_int(std::string_view token);
/// Parses decimal seconds ("12.5", "1700000000.123456789", "-0.25", "1.5e3") into nanoseconds,
/// exactly for plain decimals (no double rounding), rounded to the nearest ns otherwise.
std::optional<std::int64_t> parse_stamp_ns(std::string_view token);
/// Formats nanoseconds as decimal seconds with nine decimals ("12.300000000"): exact and sortable.
std::string format_stamp(std::int64_t stamp_ns);
/// Appends a double with a fixed number of decimals ("nan" for NaN), independent of the locale.
void append_fixed(std::string& out, double value, int decimals);
/// Appends the shortest text that reads back as exactly the same float.
void append_shortest(std::string& out, float value);
/// Reads a text file into lines (without the line ends, '\r' stripped); throws core::InputError
/// naming the file when it cannot be read.
std::vector<std::string> read_lines(const std::filesystem::path& path);
/// Reads a stamps file: one stamp in decimal seconds per line, '#' comments and blank lines
/// ignored, strictly increasing unless `require_increasing` is false; throws core::InputError
/// naming file:line otherwise.
std::vector<std::int64_t> read_stamps(const std::filesystem::path& path,
                                      bool require_increasing = true);
/// "origin_m X Y Z (world = point + origin)", metres to the millimetre: how outputs written in the
/// pipeline's local frame (maps, MCAP) state where that frame lies in the world of the poses.
std::string origin_comment(const Eigen::Vector3d& origin);
/// Reads a whole binary file; throws core::InputError naming the file when it cannot be read.
std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path);

}  // namespace ringtrack::io
