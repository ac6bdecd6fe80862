// The scene error of a text, and the check of its location and wording, shared by the tests of
// bad scene input (bad_input_test.cpp, parameters_test.cpp, routing_test.cpp).
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "screwfem/io/scene.h"
#include "screwfem/model/errors.h"

namespace screwfem::test {

// The InputError message of ParseScene(text, source, overrides), or "(no error)".
inline std::string SceneError(const std::string& text, const std::string& source,
                              const std::vector<std::string>& overrides = {}) {
  try {
    ParseScene(text, source, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

// Asserts that `message` starts with the location prefix exactly and contains `what`.
inline void ExpectErrorAt(const std::string& message, const std::string& location,
                          const std::string& what) {
  EXPECT_EQ(message.rfind(location + ": ", 0), 0u) << "message: " << message;
  EXPECT_NE(message.find(what), std::string::npos) << "message: " << message;
}

}  // namespace screwfem::test
