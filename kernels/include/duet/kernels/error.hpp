#pragma once
/// @file error.hpp
/// The one exception type of duet. Kernels and runtime throw duet::Error; the C API
/// catches it and maps code() to `enum duet_error` (bindings_c/include/duet.h).
#include <stdexcept>
#include <string>

namespace duet {

enum class ErrorCode {
  kInvalidArgument = 1,  ///< a parameter is out of its allowed range or inconsistent
  kOutOfRange = 2,       ///< input data outside what the kernel can represent (e.g. voxel index overflow)
  kIo = 3,               ///< a file could not be opened, read or written
  kParse = 4,            ///< a file or profile is malformed
  kUnsupported = 5,      ///< a valid request the library does not implement
  kOutOfMemory = 6,      ///< an allocation failed
  kInternal = 7,         ///< a bug in duet
};

class Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& what) : std::runtime_error(what), code_(code) {}
  [[nodiscard]] ErrorCode code() const noexcept { return code_; }

 private:
  ErrorCode code_;
};

[[noreturn]] inline void fail(ErrorCode code, const std::string& what) { throw Error(code, what); }

}  // namespace duet
