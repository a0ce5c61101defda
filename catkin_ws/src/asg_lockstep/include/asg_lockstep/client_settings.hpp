#pragma once
/// @file client_settings.hpp
/// What the C++ lockstep client's `~lockstep` comes to, decided as the Python client decides it
/// (asg_lockstep.ros.LockstepClient) from the one table of both (client_params.hpp, generated from
/// params.CLIENT): the node's own value wins; unset, the stack registration's `stack/mode`
/// decides ("lockstep" or not); with neither, the table's default. A value that is not true or
/// false is refused, naming the parameter and what is allowed. No ROS (the client reads the
/// parameter server and passes what it found).

#include <stdexcept>
#include <string>

#include "asg_lockstep/client_params.hpp"

namespace asg_lockstep {

/// A private parameter as read from the parameter server.
struct ParameterRead {
  enum Kind { kUnset, kBool, kOther } kind = kUnset;
  bool flag = false;  ///< the value when kind is kBool
  std::string shown;  ///< the value as an error writes it when kind is kOther ('yes', 1, 0.5)
};

/// The refusal of a registration's `stack/mode` that is not 'lockstep' or 'free' (`shown`: the
/// value as the error writes it), as asg_lockstep.params.registered_lockstep words it.
inline std::invalid_argument badRegisteredMode(const std::string& shown) {
  return std::invalid_argument("stack/mode = " + shown + ": must be 'lockstep' or 'free'");
}

/// Whether the client runs in lockstep. `registered_mode`: the registration's `stack/mode`, or
/// nullptr when the stack has none. Throws std::invalid_argument for a `~lockstep` of another
/// kind, and for a `stack/mode` that is not 'lockstep' or 'free' (issue #80: any other string ran
/// free without a word).
inline bool clientLockstep(const ParameterRead& param, const std::string* registered_mode) {
  const client_params::BoolParam& p = client_params::kLockstep;
  if (registered_mode && *registered_mode != "lockstep" && *registered_mode != "free")
    throw badRegisteredMode("'" + *registered_mode + "'");
  if (param.kind == ParameterRead::kBool) return param.flag;
  if (param.kind == ParameterRead::kOther)
    throw std::invalid_argument(std::string("~") + p.name + " = " + param.shown + ": must be " + p.allowed);
  return registered_mode ? *registered_mode == "lockstep" : p.default_value;
}

}  // namespace asg_lockstep
