#pragma once
/// @file param_reader.hpp
/// Reads a node's parameter table (asg_lockstep/param_table.hpp) from the parameter server. Each
/// value is taken as its row's kind asks: a value of another type is refused by name, where
/// NodeHandle::param would keep the default silently (a string for a number, a number for a bool),
/// and so is a value out of its range. Header-only; the ROS layer of the table.
#include <ros/ros.h>

#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "asg_lockstep/param_table.hpp"

namespace asg_lockstep {
namespace params {

/// A parameter server value as `kind` asks; "" or what the value must be.
inline std::string fromXmlRpc(const XmlRpc::XmlRpcValue& x, Kind kind, Value* v) {
  const auto t = x.getType();
  XmlRpc::XmlRpcValue copy = x;  // XmlRpcValue's conversions are not const
  switch (kind) {
    case Kind::kBool:
      if (t != XmlRpc::XmlRpcValue::TypeBoolean) return "true or false";
      v->number = bool(copy) ? 1.0 : 0.0;
      return "";
    case Kind::kInt:
    case Kind::kReal:
      if (t == XmlRpc::XmlRpcValue::TypeInt) v->number = int(copy);
      else if (t == XmlRpc::XmlRpcValue::TypeDouble) v->number = double(copy);
      else return kind == Kind::kInt ? "a whole number" : "a number";
      return "";
    case Kind::kText:
      if (t != XmlRpc::XmlRpcValue::TypeString) return "a string";
      v->text = std::string(copy);
      return "";
    case Kind::kList:
      if (t != XmlRpc::XmlRpcValue::TypeArray) return "a list of node names";
      v->list.clear();
      for (int i = 0; i < copy.size(); ++i) {
        if (copy[i].getType() != XmlRpc::XmlRpcValue::TypeString) return "a list of node names (strings)";
        v->list.push_back(std::string(copy[i]));
      }
      return "";
  }
  return "of a known kind";
}

/// The value as an error shows it: 'text' for a string, its XML otherwise.
inline std::string shown(const XmlRpc::XmlRpcValue& x) {
  XmlRpc::XmlRpcValue copy = x;
  if (x.getType() == XmlRpc::XmlRpcValue::TypeString) return "'" + std::string(copy) + "'";
  if (x.getType() == XmlRpc::XmlRpcValue::TypeBoolean) return bool(copy) ? "true" : "false";
  if (x.getType() == XmlRpc::XmlRpcValue::TypeInt) return std::to_string(int(copy));
  if (x.getType() == XmlRpc::XmlRpcValue::TypeDouble) return formatNumber(double(copy), false);
  return copy.toXml();
}

/// Reads `prefix + row.name` for every row of `table` that `keep` accepts (nullptr: every row)
/// from `nh` into *settings; an unset parameter keeps its default. Each problem goes to *errors,
/// naming the parameter as `shown_prefix + row.name` (e.g. "~camera/width").
template <class P>
void readTable(const ros::NodeHandle& nh, const std::string& prefix, const std::string& shown_prefix,
               const Table<P>& table, P* settings, std::vector<std::string>* errors,
               bool (*keep)(const Row&) = nullptr) {
  for (const auto& r : table.rows) {
    if (keep && !keep(r)) continue;
    XmlRpc::XmlRpcValue x;
    if (!nh.getParam(prefix + r.name, x)) continue;  // the default stays
    Value v;
    const std::string where = shown_prefix + r.name;
    const std::string why = fromXmlRpc(x, r.kind, &v);
    if (!why.empty()) {
      errors->push_back(where + " = " + shown(x) + ": must be " + why);
      continue;
    }
    const std::string bad = set(table, settings, r, v, where);
    if (!bad.empty()) errors->push_back(bad);
  }
}

/// Reads the one parameter `name` of `nh` as `kind` into *v, as readTable reads a row: false when
/// it is unset, or when it holds another type, which goes to *errors naming it.
inline bool readOne(const ros::NodeHandle& nh, const std::string& name, Kind kind, Value* v,
                    std::vector<std::string>* errors) {
  XmlRpc::XmlRpcValue x;
  if (!nh.getParam(name, x)) return false;
  const std::string why = fromXmlRpc(x, kind, v);
  if (why.empty()) return true;
  errors->push_back(name + " = " + shown(x) + ": must be " + why);
  return false;
}

/// "bad parameter: A" or "bad parameters: A; B" ("" when there is none).
inline std::string joinErrors(const std::vector<std::string>& errors) {
  if (errors.empty()) return "";
  std::string all = errors.size() > 1 ? "bad parameters: " : "bad parameter: ";
  for (size_t i = 0; i < errors.size(); ++i) all += (i ? "; " : "") + errors[i];
  return all;
}

/// Reads the node's private table and throws std::invalid_argument naming every bad value.
template <class P>
P readPrivate(const ros::NodeHandle& pnh, const Table<P>& table) {
  P settings{};
  std::vector<std::string> errors;
  readTable(pnh, "", "~", table, &settings, &errors);
  if (!errors.empty()) throw std::invalid_argument(joinErrors(errors));
  return settings;
}

/// For main(): `NODE --params` prints the table and returns true (the caller exits 0).
template <class P>
bool printedTable(int argc, char** argv, const Table<P>& table) {
  if (argc != 2 || std::strcmp(argv[1], "--params") != 0) return false;
  std::fputs(markdown(table).c_str(), stdout);
  return true;
}

}  // namespace params
}  // namespace asg_lockstep
