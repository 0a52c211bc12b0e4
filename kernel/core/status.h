// Errors that cross the kernel boundary as values, never as exceptions.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <variant>

namespace gk {

// kStopped: the caller asked to stop (a deadline passed, the call was cancelled): no answer.
// kResourceExhausted: a bounded queue is full (retry later).
enum class ErrorCode { kInvalidArgument, kNotFound, kFailedPrecondition, kInternal, kStopped, kResourceExhausted };

struct Error {
  ErrorCode code = ErrorCode::kInvalidArgument;
  std::string field;    // which input was wrong, e.g. "vertices[12].z"
  std::string message;  // what was wrong with it

  std::string to_string() const { return field.empty() ? message : field + ": " + message; }
};

inline Error invalid_argument(std::string field, std::string message) {
  return {ErrorCode::kInvalidArgument, std::move(field), std::move(message)};
}

// The caller asked to stop (a deadline, a cancel, or its own time budget) during `what`.
inline Error stopped(std::string what) { return {ErrorCode::kStopped, "", "stopped (deadline, cancellation or time budget) during " + std::move(what)}; }

template <typename T>
class [[nodiscard]] Result {
 public:
  Result(T value) : state_(std::move(value)) {}  // NOLINT: implicit by design
  Result(Error error) : state_(std::move(error)) {}  // NOLINT

  bool ok() const { return std::holds_alternative<T>(state_); }
  const T& value() const& { return std::get<T>(state_); }
  T& value() & { return std::get<T>(state_); }
  T&& value() && { return std::get<T>(std::move(state_)); }
  const Error& error() const { return std::get<Error>(state_); }

 private:
  std::variant<T, Error> state_;
};

}  // namespace gk
