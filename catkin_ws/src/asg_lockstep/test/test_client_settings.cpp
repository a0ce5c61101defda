// The C++ lockstep client's `~lockstep`, decided as the Python client decides it (issue #56).
#include <gtest/gtest.h>

#include <string>

#include "asg_lockstep/client_settings.hpp"

using asg_lockstep::clientLockstep;
using asg_lockstep::ParameterRead;

TEST(ClientSettings, TheNodesValueWinsOverItsRegistration) {
  const std::string free_mode = "free", lockstep = "lockstep";
  EXPECT_FALSE(clientLockstep({ParameterRead::kBool, false, ""}, &lockstep));
  EXPECT_TRUE(clientLockstep({ParameterRead::kBool, true, ""}, &free_mode));
}

TEST(ClientSettings, UnsetTheRegistrationDecidesElseTheTablesDefault) {
  const std::string free_mode = "free", lockstep = "lockstep";
  EXPECT_FALSE(clientLockstep({}, &free_mode));
  EXPECT_TRUE(clientLockstep({}, &lockstep));
  EXPECT_EQ(clientLockstep({}, nullptr), asg_lockstep::client_params::kLockstep.default_value);
}

TEST(ClientSettings, AValueOfAnotherKindIsRefusedByName) {
  try {
    clientLockstep({ParameterRead::kOther, false, "'yes'"}, nullptr);
    FAIL() << "accepted ~lockstep = 'yes'";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "~lockstep = 'yes': must be true or false");  // the Python client's words
  }
}

TEST(ClientSettings, ARegistrationModeOtherThanLockstepOrFreeIsRefusedByName) {
  // issue #80: any other string ran free without a word; the Python client's words
  // (asg_lockstep.params.registered_lockstep)
  const std::string typo = "lock-step";
  for (const ParameterRead& own : {ParameterRead{}, ParameterRead{ParameterRead::kBool, true, ""}}) {
    try {
      clientLockstep(own, &typo);
      FAIL() << "accepted stack/mode = 'lock-step'";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), "stack/mode = 'lock-step': must be 'lockstep' or 'free'");
    }
  }
  EXPECT_EQ(std::string(asg_lockstep::badRegisteredMode("1").what()), "stack/mode = 1: must be 'lockstep' or 'free'");
}
