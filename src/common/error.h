// Error types used inside the library (C++ layer). The C API and the plugin boundary catch
// all of them and turn them into emf_status + message (src/capi/).
#pragma once

#include <stdexcept>
#include <string>

namespace emf {

/// Base of every exception thrown by emf. `what()` is a complete, user-facing sentence that
/// names the file/key/frame involved and, where possible, what to do.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A configuration file, key or value is wrong (unknown key, wrong type, out of range).
class ConfigError : public Error {
 public:
  using Error::Error;
};

/// A file or dataset could not be read or written, or its contents are inconsistent.
class IoError : public Error {
 public:
  using Error::Error;
};

/// A caller passed an invalid argument to a library function.
class InvalidArgument : public Error {
 public:
  using Error::Error;
};

/// A fixed-size resource (memory pool, ring) is exhausted where that cannot be tolerated.
class ResourceError : public Error {
 public:
  using Error::Error;
};

/// A call is not valid in the object's current state (e.g. a runtime started after stop(), a
/// frame processed before the intrinsics were set). The message says what to call first.
class StateError : public Error {
 public:
  using Error::Error;
};

/// Something named by the caller does not exist (an object id, a device, a plugin).
class NotFoundError : public Error {
 public:
  using Error::Error;
};

}  // namespace emf
