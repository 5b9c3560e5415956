#pragma once
/// @file errors.hpp
/// Exceptions thrown by the sorpia core. Every one says what is wrong and where
/// (vertex, face or edge index; line number in a file).

#include <stdexcept>
#include <string>

namespace sorpia {

/// The mesh given by the caller is not one the scheme can run on (bad index,
/// repeated vertex, non-manifold edge, a non-triangle under Loop, ...). Maps to Python's ValueError.
class MeshError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A parameter is out of range (omega, tol, max_iter, unknown name).
/// Maps to Python's ValueError.
class ParameterError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A mesh file cannot be read or written (missing, truncated, malformed).
/// Maps to Python's ValueError (a subclass of it, sorpia.MeshFileError).
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace sorpia
