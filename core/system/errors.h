#pragma once
/// Exceptions thrown by seamvox. Every message says what is wrong, where (file, line, element,
/// face index) and, where it helps, what to do about it.
#include <stdexcept>
#include <string>

namespace seamvox {

/// Base of every seamvox exception.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
/// A file could not be opened, read or written (missing, truncated, permissions, disk full).
class IoError : public Error {
 public:
  using Error::Error;
};
/// The input is readable but its content is invalid (bad header, index out of range, NaN).
class InputError : public Error {
 public:
  using Error::Error;
};
/// A mesh does not have the topology a stage requires (non-manifold, empty, not a disk).
class TopologyError : public Error {
 public:
  using Error::Error;
};
/// A numerical stage failed (factorization not positive definite, out of memory).
class SolverError : public Error {
 public:
  using Error::Error;
};
/// A long stage was cancelled through its progress callback.
class CancelledError : public Error {
 public:
  using Error::Error;
};

/// Inside a catch block: rethrows the current seamvox error as the same type with
/// "context: " before its message (e.g. the file a stage was working on); anything else is
/// rethrown unchanged. A message that already starts with the context is not prefixed again.
[[noreturn]] void rethrowWithContext(const std::string& context);

}  // namespace seamvox
