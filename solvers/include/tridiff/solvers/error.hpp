// The exceptions of tridiff: misuse (a wrong argument) and numerical breakdown (a zero pivot,
// a non-finite value) are both reported by throwing, naming what is at fault.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace tridiff {

// Base of every exception the library throws.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;

  // A batch solve that failed in several systems throws the error of the first and lists the
  // others here: the first failing systems, ascending (at most kListedFailures of them), and
  // how many failed in all. Empty and 0 for an error not tied to the systems of a batch.
  static constexpr std::size_t kListedFailures = 8;
  const std::vector<std::ptrdiff_t>& failed_systems() const noexcept { return failed_systems_; }
  std::ptrdiff_t failed_count() const noexcept { return failed_count_; }
  void set_failures(std::vector<std::ptrdiff_t> first_systems, std::ptrdiff_t count) {
    failed_systems_ = std::move(first_systems);
    failed_count_ = count;
  }

 private:
  std::vector<std::ptrdiff_t> failed_systems_;
  std::ptrdiff_t failed_count_ = 0;
};

// An argument is wrong: a size, a stride, a pointer, a coefficient that is not finite.
// `system()` and `row()` are -1 when the fault is not tied to one element.
class InvalidArgument : public Error {
 public:
  InvalidArgument(std::string argument, std::ptrdiff_t system, std::ptrdiff_t row,
                  const std::string& message)
      : Error(compose(argument, system, row, message)),
        argument_(std::move(argument)),
        message_(message),
        system_(system),
        row_(row) {}

  // A fault of the argument as a whole, not of one system or row.
  InvalidArgument(std::string argument, const std::string& message)
      : InvalidArgument(std::move(argument), -1, -1, message) {}

  const std::string& argument() const noexcept { return argument_; }
  // What is wrong, without the argument, system and row that what() puts before it.
  const std::string& message() const noexcept { return message_; }
  std::ptrdiff_t system() const noexcept { return system_; }
  std::ptrdiff_t row() const noexcept { return row_; }

 private:
  static std::string compose(const std::string& argument, std::ptrdiff_t system, std::ptrdiff_t row,
                             const std::string& message) {
    std::string where = "argument '" + argument + "'";
    if (system >= 0) where += ", system " + std::to_string(system);
    if (row >= 0) where += ", row " + std::to_string(row);
    return "tridiff: " + where + ": " + message;
  }

  std::string argument_;
  std::string message_;
  std::ptrdiff_t system_;
  std::ptrdiff_t row_;
};

// The numbers broke down: a zero or vanishing pivot (the system is singular to working
// precision), an overflow, or a system the chosen method cannot solve safely.
// `system()` and `row()` are -1 when the fault is not tied to one; what() then omits them.
class NumericalError : public Error {
 public:
  NumericalError(std::ptrdiff_t system, std::ptrdiff_t row, const std::string& message)
      : Error(compose(system, row, message)), message_(message), system_(system), row_(row) {}

  // What went wrong, without the system and row that what() puts before it.
  const std::string& message() const noexcept { return message_; }
  std::ptrdiff_t system() const noexcept { return system_; }
  std::ptrdiff_t row() const noexcept { return row_; }

 private:
  static std::string compose(std::ptrdiff_t system, std::ptrdiff_t row,
                             const std::string& message) {
    std::string where;
    if (system >= 0) where = "system " + std::to_string(system);
    if (row >= 0) where += (where.empty() ? "row " : ", row ") + std::to_string(row);
    return "tridiff: " + (where.empty() ? std::string() : where + ": ") + message;
  }

  std::string message_;
  std::ptrdiff_t system_;
  std::ptrdiff_t row_;
};

}  // namespace tridiff
