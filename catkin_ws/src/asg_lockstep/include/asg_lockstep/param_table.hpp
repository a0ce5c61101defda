#pragma once
/// @file param_table.hpp
/// One parameter table for every C++ node of the project (issue #69): a row per private
/// parameter, with its name as the node reads it, kind, unit, range and meaning, and the field of
/// the node's settings struct it fills. The node reads through the table (ros/param_reader.hpp:
/// a value of another type or out of range is refused, naming the parameter), `NODE --params`
/// prints it (markdown()), and the docs quote that output (tests/test_node_parameters.py), so a
/// parameter is written once. Header-only; no ROS.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <string>
#include <vector>

namespace asg_lockstep {
namespace params {

enum class Kind { kReal, kInt, kBool, kText, kList };

/// One parameter's value, whatever its kind (numbers, bools as 0/1, text, a list of names).
struct Value {
  double number = 0.0;
  std::string text;
  std::vector<std::string> list;
};

/// One row of a node's table: a parameter and the field of the node's settings struct it fills
/// (get/set, written by the ASG_PARAM_* macros below for the struct the Table names).
struct Row {
  const char* name;         ///< as the node reads it (private), e.g. "follower/kp"
  Kind kind;
  const char* unit;         ///< "-" when dimensionless
  double lo, hi;            ///< range of numbers, inclusive unless `open`
  bool open;                ///< the range excludes both ends
  const char* range_text;   ///< the range as the docs write it
  const char* description;  ///< one line for the docs
  Value (*get)(const void* settings);
  void (*set)(void* settings, const Value&);  ///< no checks; use params::set
  std::vector<std::string> choices{};         ///< the only texts allowed (empty: any)
  std::vector<double> number_choices{};       ///< the only numbers allowed (empty: any in range)
  bool registration = false;                  ///< a stack registration may set it (the scene worker's)
};

/// The table of a node whose settings struct is P (defaults: P's own), rows in the docs' order.
template <class P>
struct Table {
  Table(std::initializer_list<Row> r) : rows(r) {}
  std::vector<Row> rows;
};

/// Fixed-point text of a number as the docs write it ("5.0", "3").
inline std::string formatNumber(double v, bool integral) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), integral ? "%.0f" : "%.15g", v);
  std::string s = buf;
  if (!integral && s.find_first_of(".en") == std::string::npos) s += ".0";
  return s;
}

/// The value as the docs write it ("30.0", "256", "true", "`[planner]`", "`\"\"`").
inline std::string formatValue(Kind kind, const Value& value) {
  switch (kind) {
    case Kind::kBool:
      return value.number != 0.0 ? "true" : "false";
    case Kind::kInt:
      return formatNumber(value.number, true);
    case Kind::kReal:
      return formatNumber(value.number, false);
    case Kind::kText:
      return value.text.empty() ? "`\"\"`" : value.text;
    case Kind::kList: {
      std::string s = "`[";
      for (size_t i = 0; i < value.list.size(); ++i) s += (i ? ", " : "") + value.list[i];
      return s + "]`";
    }
  }
  return "";
}

/// "" when `value` fits the row's kind and range, else what is wrong, naming the parameter as
/// `where` gives it ("~camera/width", "stack/worker/points_stride", "planner parameter 'x'").
inline std::string check(const Row& r, const Value& value, const std::string& where) {
  auto bad = [&](const std::string& must) { return where + " = " + formatValue(r.kind, value) + ": must be " + must; };
  const double v = value.number;
  if (r.kind == Kind::kReal || r.kind == Kind::kInt) {
    if (!std::isfinite(v)) return bad("a finite number");
    if (r.kind == Kind::kInt && v != std::floor(v)) return bad("a whole number");
    if (!r.number_choices.empty()) {
      if (std::find(r.number_choices.begin(), r.number_choices.end(), v) == r.number_choices.end())
        return bad(r.range_text);
      return "";
    }
    const bool in = r.open ? (v > r.lo && v < r.hi) : (v >= r.lo && v <= r.hi);
    if (!in) return bad(std::string("in ") + r.range_text + (r.unit[0] == '-' ? "" : std::string(" [") + r.unit + "]"));
  } else if (r.kind == Kind::kBool && v != 0.0 && v != 1.0) {
    return bad("true or false");
  } else if (r.kind == Kind::kText && !r.choices.empty() &&
             std::find(r.choices.begin(), r.choices.end(), value.text) == r.choices.end()) {
    return bad(std::string("one of ") + r.range_text);
  } else if (r.kind == Kind::kList) {
    for (const auto& name : value.list)
      if (name.empty()) return bad("a list of node names (one is empty)");
  }
  return "";
}

/// Checks `value` (check()) and sets it; returns "" or what is wrong.
template <class P>
std::string set(const Table<P>&, P* settings, const Row& r, const Value& value, const std::string& where) {
  std::string why = check(r, value, where);
  if (why.empty()) r.set(settings, value);
  return why;
}

/// The row named `name`, nullptr when the table has none.
template <class P>
const Row* find(const Table<P>& table, const std::string& name) {
  for (const auto& r : table.rows)
    if (name == r.name) return &r;
  return nullptr;
}

/// The table's rows as the docs quote them, one `| parameter | unit | default | range | meaning |`
/// line each, with the defaults of P; `registration`: a column before the meaning saying which
/// rows a stack registration may set; `required`: the default cell of a list row whose default
/// is empty.
template <class P>
std::string markdownRows(const Table<P>& table, bool registration = false, const char* required = nullptr) {
  const P defaults{};
  std::string out;
  for (const auto& r : table.rows) {
    const Value v = r.get(&defaults);
    const std::string cell =
        required && r.kind == Kind::kList && v.list.empty() ? std::string(required) : formatValue(r.kind, v);
    out += std::string("| `") + r.name + "` | " + r.unit + " | " + cell + " | " + r.range_text + " | " +
           (registration ? std::string(r.registration ? "yes" : "-") + " | " : std::string()) + r.description + " |\n";
  }
  return out;
}

/// The table as the docs quote it (`NODE --params`): the header, then markdownRows().
template <class P>
std::string markdown(const Table<P>& table, bool registration = false, const char* required = nullptr) {
  const std::string header = registration ? "| parameter | unit | default | range | a registration may set it | meaning |\n"
                                            "|---|---|---|---|---|---|\n"
                                          : "| parameter | unit | default | range | meaning |\n|---|---|---|---|---|\n";
  return header + markdownRows(table, registration, required);
}

}  // namespace params
}  // namespace asg_lockstep

// get/set of one field of P, as captureless lambdas (the Row's function pointers):
//   {"camera/width", Kind::kInt, ..., ASG_PARAM_NUMBER(WorkerParams, width)}
#define ASG_PARAM_NUMBER(P, field)                                                             \
  [](const void* s) {                                                                          \
    ::asg_lockstep::params::Value v;                                                           \
    v.number = double(static_cast<const P*>(s)->field);                                        \
    return v;                                                                                  \
  },                                                                                           \
      [](void* s, const ::asg_lockstep::params::Value& v) {                                    \
        auto* p = static_cast<P*>(s);                                                          \
        p->field = decltype(p->field)(v.number);                                               \
      }
#define ASG_PARAM_FLAG(P, field)                                                               \
  [](const void* s) {                                                                          \
    ::asg_lockstep::params::Value v;                                                           \
    v.number = static_cast<const P*>(s)->field ? 1.0 : 0.0;                                    \
    return v;                                                                                  \
  },                                                                                           \
      [](void* s, const ::asg_lockstep::params::Value& v) { static_cast<P*>(s)->field = v.number != 0.0; }
#define ASG_PARAM_TEXT(P, field)                                                               \
  [](const void* s) {                                                                          \
    ::asg_lockstep::params::Value v;                                                           \
    v.text = static_cast<const P*>(s)->field;                                                  \
    return v;                                                                                  \
  },                                                                                           \
      [](void* s, const ::asg_lockstep::params::Value& v) { static_cast<P*>(s)->field = v.text; }
#define ASG_PARAM_LIST(P, field)                                                               \
  [](const void* s) {                                                                          \
    ::asg_lockstep::params::Value v;                                                           \
    v.list = static_cast<const P*>(s)->field;                                                  \
    return v;                                                                                  \
  },                                                                                           \
      [](void* s, const ::asg_lockstep::params::Value& v) { static_cast<P*>(s)->field = v.list; }
