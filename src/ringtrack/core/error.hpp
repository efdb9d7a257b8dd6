#pragma once
/// Error types shared by every module. Messages name the file, offset or key and what was expected.

#include <stdexcept>
#include <string>

namespace ringtrack::core {

/// Base of every error ringtrack throws on purpose; the CLI prints what() on one line.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A configuration key is unknown, malformed or out of range.
class ConfigError : public Error {
 public:
  using Error::Error;
};

/// An input file or stream is missing, truncated or malformed.
class InputError : public Error {
 public:
  using Error::Error;
};

}  // namespace ringtrack::core
