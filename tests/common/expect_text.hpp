// Text expectations for tests of messages and outputs, and the messages of exceptions.
#pragma once

#include "lexdyn/common/error.hpp"

#include <gtest/gtest.h>

#include <initializer_list>
#include <string>

namespace lexdyn::testing {

/// Success when `text` contains every one of `parts`; a failure names the parts not found and
/// shows the text. EXPECT_TRUE(containsAll(message, {"file.yaml:3: key", "expected"})).
inline ::testing::AssertionResult containsAll(const std::string& text, std::initializer_list<std::string> parts) {
  std::string missing;
  for (const std::string& p : parts) {
    if (text.find(p) == std::string::npos) missing += " '" + p + "'";
  }
  if (missing.empty()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "not found:" << missing << " in:\n" << text;
}

/// part(e) of the exception e of type E that `f()` throws, or `none` (an exception of another
/// type goes through).
template <class E, class F, class Part>
std::string ofException(F&& f, Part part, const char* none) {
  try {
    f();
  } catch (const E& e) {
    return part(e);
  }
  return none;
}

/// The message of the exception of type E that `f()` throws, or "<no error>".
template <class E, class F>
std::string exceptionMessage(F&& f) {
  return ofException<E>(
      f, [](const E& e) { return std::string(e.what()); }, "<no error>");
}

/// The message of the lexdyn::InputError that `f()` throws, or "<no error>".
template <class F>
std::string inputErrorOf(F&& f) {
  return exceptionMessage<InputError>(f);
}

/// Where the lexdyn::InputError that `f()` throws was found (InputError::where()), or "none".
template <class F>
std::string inputErrorWhere(F&& f) {
  return ofException<InputError>(
      f, [](const InputError& e) { return e.where(); }, "none");
}

}  // namespace lexdyn::testing
