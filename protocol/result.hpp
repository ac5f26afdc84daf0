// Result<T>: a value or an error (a C++20 stand-in for std::expected<T, Error>). Used wherever bad
// external input (bytes, peers) must come back as a value, never as a crash or an escaping
// exception. Checks that produce no value return std::optional<std::string> (nullopt = fine, else
// the reason), like Camera::invalid_reason().
// An error's reason is for people; a caller that must act on what went wrong reads its kind,
// never the reason's text.
#pragma once
#include <string>
#include <utility>
#include <variant>

namespace occ {

enum class ErrorKind {
  other,    // anything else: the reason says what
  timeout,  // nothing (valid) came within the time given: waiting again may help
  busy,     // the peer refused us because it already serves our slot (wire.hpp kByeBusy): try later
};

struct Error {
  std::string reason;
  ErrorKind kind = ErrorKind::other;
};

template <class T>
class [[nodiscard]] Result {
 public:
  Result(T value) : v_(std::in_place_index<0>, std::move(value)) {}
  Result(Error error) : v_(std::in_place_index<1>, std::move(error)) {}

  bool ok() const { return v_.index() == 0; }
  explicit operator bool() const { return ok(); }

  // Preconditions: ok() for value access, !ok() for error().
  T& value() & { return std::get<0>(v_); }
  const T& value() const& { return std::get<0>(v_); }
  T&& value() && { return std::get<0>(std::move(v_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }
  const std::string& error() const { return std::get<1>(v_).reason; }
  ErrorKind error_kind() const { return std::get<1>(v_).kind; }

 private:
  std::variant<T, Error> v_;
};

}  // namespace occ
