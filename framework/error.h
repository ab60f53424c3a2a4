// SPDX-License-Identifier: MIT
#pragma once

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace harap {

/// Base of every exception harap throws. Library code never exits or aborts; only main() turns
/// these into exit codes.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Bad configuration: unknown registry name, unknown or invalid option, malformed scenario.
/// The message names the file/key and lists the valid alternatives where there are any.
class ConfigError : public Error {
 public:
  using Error::Error;
};

/// Unreadable or invalid input data (mesh files, index files): names the file and the problem.
class InputError : public Error {
 public:
  using Error::Error;
};

/// A numerical failure that cannot be recovered (matrix not positive definite, out of memory in a
/// factorization). The message says what to try instead.
class NumericalError : public Error {
 public:
  using Error::Error;
};

/// A broken precondition or internal invariant: a bug in harap or in a caller of the library.
class InternalError : public Error {
 public:
  using Error::Error;
};

}  // namespace harap

/// Checks a precondition in all build types (unlike assert) and throws harap::InternalError.
#define HARAP_CHECK(condition, ...)                                                                \
  do {                                                                                             \
    if (!(condition)) {                                                                            \
      throw ::harap::InternalError(fmt::format("{}:{}: check `{}` failed: {}", __FILE__, __LINE__, \
                                               #condition, fmt::format(__VA_ARGS__)));             \
    }                                                                                              \
  } while (false)
