// The message of the exception of type Error that an action throws; a test failure when it throws none.
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace ph {

template <typename Error, typename Action>
std::string thrown_message(const Action& action) {
  try {
    action();
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "the expected exception was not thrown";
  return {};
}

}  // namespace ph
