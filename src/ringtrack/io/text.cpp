#include "ringtrack/io/text.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {

std::vector<std::string_view> split_tokens(std::string_view line, bool commas) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  const auto is_sep = [commas](char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || (commas && c == ',');
  };
  while (i < line.size()) {
    while (i < line.size() && is_sep(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_sep(line[i])) ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

std::optional<double> parse_double(std::string_view token) {
  if (token.empty()) return std::nullopt;
  // from_chars rejects a leading '+', which some writers emit.
  if (token.front() == '+') token.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
  return value;
}

std::optional<std::int64_t> parse_int(std::string_view token) {
  if (token.empty()) return std::nullopt;
  if (token.front() == '+') token.remove_prefix(1);
  std::int64_t value = 0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
  return value;
}

std::optional<std::int64_t> parse_stamp_ns(std::string_view token) {
  std::string_view s = token;
  bool negative = false;
  if (!s.empty() && (s.front() == '-' || s.front() == '+')) {
    negative = s.front() == '-';
    s.remove_prefix(1);
  }
  const auto dot = s.find('.');
  const std::string_view whole = s.substr(0, dot);
  const std::string_view frac =
      dot == std::string_view::npos ? std::string_view{} : s.substr(dot + 1);
  const auto all_digits = [](std::string_view t) {
    for (char c : t) {
      if (c < '0' || c > '9') return false;
    }
    return true;
  };
  if (!whole.empty() && all_digits(whole) && all_digits(frac) && whole.size() <= 10) {
    std::int64_t seconds = 0;
    for (char c : whole) seconds = seconds * 10 + (c - '0');
    if (seconds > 9'000'000'000) return std::nullopt;  // beyond int64 nanoseconds
    std::int64_t nanos = 0;
    for (std::size_t k = 0; k < 9; ++k) nanos = nanos * 10 + (k < frac.size() ? frac[k] - '0' : 0);
    // Round half up on the tenth decimal; further digits cannot change the result except ties.
    if (frac.size() > 9 && frac[9] >= '5') ++nanos;
    const std::int64_t ns = seconds * 1'000'000'000 + nanos;
    return negative ? -ns : ns;
  }
  // Exponent notation and other forms: through double (sub-microsecond rounding for epoch stamps).
  const auto value = parse_double(token);
  if (!value || !std::isfinite(*value) || std::abs(*value) > 9.2e9) return std::nullopt;
  return static_cast<std::int64_t>(std::llround(*value * 1e9));
}

std::string format_stamp(std::int64_t stamp_ns) {
  const bool negative = stamp_ns < 0;
  // Work with the magnitude as unsigned so INT64_MIN cannot overflow.
  const std::uint64_t mag =
      negative ? 0 - static_cast<std::uint64_t>(stamp_ns) : static_cast<std::uint64_t>(stamp_ns);
  const std::string frac = std::to_string(mag % 1'000'000'000u);
  std::string out;
  if (negative) out.push_back('-');
  out += std::to_string(mag / 1'000'000'000u);
  out.push_back('.');
  out.append(9 - frac.size(), '0');
  out += frac;
  return out;
}

void append_fixed(std::string& out, double value, int decimals) {
  if (std::isnan(value)) {
    out += "nan";
    return;
  }
  char buf[64];
  auto result = std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::fixed, decimals);
  if (result.ec != std::errc()) {
    // Only absurdly large magnitudes fail with 64 characters; fall back to scientific notation.
    result = std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::scientific, decimals);
  }
  std::string_view text(buf, static_cast<std::size_t>(result.ptr - buf));
  // "-0.000" carries no information beyond "0.000" and breaks byte-identical comparisons.
  if (text.front() == '-' && text.find_first_not_of("-0.") == std::string_view::npos) {
    text.remove_prefix(1);
  }
  out += text;
}

void append_shortest(std::string& out, float value) {
  if (std::isnan(value)) {
    out += "nan";
    return;
  }
  char buf[32];
  const auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  out.append(buf, static_cast<std::size_t>(ptr - buf));
}

std::vector<std::uint8_t> read_file_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw core::InputError(path.string() + ": expected a file, found a directory");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int e = errno;
    throw core::InputError(path.string() +
                           ": cannot open file: " + (e != 0 ? std::strerror(e) : "unknown error"));
  }
  std::vector<std::uint8_t> bytes;
  in.seekg(0, std::ios::end);
  const auto end = in.tellg();
  in.seekg(0, std::ios::beg);
  if (end < 0) throw core::InputError(path.string() + ": cannot determine the file size");
  bytes.resize(static_cast<std::size_t>(end));
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<std::size_t>(in.gcount()) != bytes.size()) {
    throw core::InputError(path.string() + ": read error after " + std::to_string(in.gcount()) +
                           " of " + std::to_string(bytes.size()) + " bytes");
  }
  return bytes;
}

std::vector<std::string> read_lines(const std::filesystem::path& path) {
  const auto bytes = read_file_bytes(path);
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= bytes.size(); ++i) {
    if (i == bytes.size() || bytes[i] == '\n') {
      if (i == bytes.size() && i == start) break;  // no empty line after the final '\n'
      std::string line(reinterpret_cast<const char*>(bytes.data()) + start, i - start);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      lines.push_back(std::move(line));
      start = i + 1;
    }
  }
  return lines;
}

std::vector<std::int64_t> read_stamps(const std::filesystem::path& path, bool require_increasing) {
  const auto lines = read_lines(path);
  std::vector<std::int64_t> stamps;
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const auto tokens = split_tokens(lines[n]);
    if (tokens.empty() || tokens.front().front() == '#') continue;
    const std::string where = path.string() + ":" + std::to_string(n + 1);
    if (tokens.size() != 1) {
      throw core::InputError(where + ": expected one stamp in seconds, got " +
                             std::to_string(tokens.size()) + " values");
    }
    const auto ns = parse_stamp_ns(tokens.front());
    if (!ns) {
      throw core::InputError(where + ": expected a stamp in seconds, got '" +
                             std::string(tokens.front()) + "'");
    }
    if (require_increasing && !stamps.empty() && *ns <= stamps.back()) {
      throw core::InputError(where + ": stamp " + format_stamp(*ns) +
                             " does not increase (previous " + format_stamp(stamps.back()) + ")");
    }
    stamps.push_back(*ns);
  }
  return stamps;
}

std::string origin_comment(const Eigen::Vector3d& origin) {
  char line[160];
  std::snprintf(line, sizeof line, "origin_m %.3f %.3f %.3f (world = point + origin)", origin.x(),
                origin.y(), origin.z());
  return line;
}

}  // namespace ringtrack::io
