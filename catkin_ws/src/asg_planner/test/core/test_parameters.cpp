// The planner's parameter table (parameters.hpp): one row per field, defaults read from
// PlannerParams, every value checked on the way in.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "asg_planner/parameters.hpp"

using namespace asg_planner;

TEST(Parameters, NamesAreUniqueAndEachRowReachesItsOwnField) {
  std::set<std::string> names;
  const PlannerParams defaults;
  for (const auto& s : plannerParameters().rows) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_STRNE(s.unit, "") << s.name;
    EXPECT_GE(parameterValue(s, defaults), s.lo) << s.name;  // the default is in its own range
    EXPECT_LE(parameterValue(s, defaults), s.hi) << s.name;
    // Setting a row changes its field and no other row's.
    PlannerParams p;
    const double v = s.kind == asg_lockstep::params::Kind::kBool
                         ? 1.0 - parameterValue(s, p)
                         : (s.number_choices.empty() ? s.lo : s.number_choices[0]);
    if (v == parameterValue(s, p)) continue;
    setParameter(&p, s.name, v);
    for (const auto& o : plannerParameters().rows)
      EXPECT_EQ(parameterValue(o, p), std::string(o.name) == s.name ? v : parameterValue(o, defaults))
          << s.name << " moved " << o.name;
  }
  EXPECT_EQ(names.size(), 23u);  // a new field of PlannerParams needs its row (and docs/planner.md's)
}

TEST(Parameters, BadValuesAreRefusedWithTheParameterNamed) {
  PlannerParams p;
  auto message = [&](const std::string& name, double v) {
    try {
      setParameter(&p, name, v);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message("follower/kpp", 1.0), "unknown planner parameter 'follower/kpp'");
  EXPECT_EQ(message("vote_spacing", 0.0), "planner parameter 'vote_spacing' = 0.0: must be in 0.1..100 [m]");
  EXPECT_EQ(message("astar/edge_points", 2.0), "planner parameter 'astar/edge_points' = 2: must be 1 or 3");
  EXPECT_EQ(message("projection/stride", 2.5).find("must be a whole number") != std::string::npos, true);
  EXPECT_EQ(message("follower/first_crossing", 2.0),
            "planner parameter 'follower/first_crossing' = true: must be true or false");
  EXPECT_NE(message("follower/kp", std::nan("")).find("must be a finite number"), std::string::npos);
  EXPECT_EQ(p.vote_spacing, PlannerParams().vote_spacing);  // nothing refused was stored
  EXPECT_EQ(message("astar/edge_points", 1.0), "accepted");
  EXPECT_EQ(p.astar.edge_points, 1);
}

TEST(Parameters, TheDocsTableHasOneRowPerParameterWithTheDefaults) {
  const std::string md = parameterTableMarkdown();
  EXPECT_NE(md.find("| `vote_spacing` | m | 5.0 | 0.1..100 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `astar/alpha` | - | 0.02 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `follower/first_crossing` | - | false | bool |"), std::string::npos) << md;
  size_t rows = 0;
  for (char c : md) rows += c == '\n';
  EXPECT_EQ(rows, plannerParameters().rows.size() + 2);
}
