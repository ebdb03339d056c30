#pragma once
// Expected<T>: a value or an error message, for failures that are part of normal operation
// (a missing file, a malformed line, a bad message). Programming errors are assertions.
#include <cassert>
#include <string>
#include <utility>
#include <variant>

namespace rgbdslam {

struct Error {
  std::string message;  // says what failed and names the file, line or key involved
};

template <typename T>
class Expected {
 public:
  Expected(T value) : data_(std::move(value)) {}          // NOLINT: implicit by design
  Expected(Error error) : data_(std::move(error)) {}      // NOLINT: implicit by design

  bool ok() const { return std::holds_alternative<T>(data_); }
  explicit operator bool() const { return ok(); }

  const T& value() const& { assert(ok()); return std::get<T>(data_); }
  T& value() & { assert(ok()); return std::get<T>(data_); }
  T&& value() && { assert(ok()); return std::get<T>(std::move(data_)); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

  const std::string& error() const { assert(!ok()); return std::get<Error>(data_).message; }

 private:
  std::variant<T, Error> data_;
};

// Status of an operation without a value: ok, or an error message.
class Status {
 public:
  Status() = default;
  Status(Error error) : ok_(false), message_(std::move(error.message)) {}  // NOLINT
  bool ok() const { return ok_; }
  explicit operator bool() const { return ok_; }
  const std::string& error() const { return message_; }

 private:
  bool ok_ = true;
  std::string message_;
};

}  // namespace rgbdslam
