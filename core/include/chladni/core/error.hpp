#pragma once
// Errors are exceptions inside the library; the CLI maps them to exit codes (DESIGN.md):
// InputError -> 2 (the user's data or arguments are wrong), BudgetError -> 3 (more memory than
// allowed), anything else -> 1.
#include <stdexcept>
#include <string>

namespace chladni {

/// Bad input: a malformed file, an invalid parameter, a NaN. The message names what and where.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The work asked for does not fit the memory budget (--max-memory): exit code 3, so a batch
/// can tell it from other bad input and retry with more memory.
class BudgetError : public InputError {
 public:
  using InputError::InputError;
};

/// `e` with `file` named first (a problem found in what `file` asks for, such as a scene's
/// event), unless its message already starts with it.
inline InputError naming_file(const std::string& file, const InputError& e) {
  const std::string msg = e.what();
  if (msg.rfind(file, 0) == 0) return e;
  return InputError(file + ": " + msg);
}

/// A failure of ours or of the system (driver, out of memory) rather than of the input.
class InternalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace chladni
