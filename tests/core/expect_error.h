#pragma once

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "delta/core/error.h"

namespace delta {

/// Runs `call`, which must throw delta::Error whose message holds every one of `parts`.
template <typename Call>
void expectErrorSaying(const Call& call, const std::vector<std::string>& parts) {
  try {
    call();
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    for (const std::string& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos)
          << "\"" << part << "\" not in: " << e.what();
  }
}

}  // namespace delta
