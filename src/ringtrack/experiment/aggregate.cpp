#include "ringtrack/experiment/aggregate.hpp"

#include <utility>

namespace ringtrack::experiment {
namespace {

Aggregate named(std::string label) {
  Aggregate a;
  a.label = std::move(label);
  return a;
}

}  // namespace

void Aggregate::add(const BenchmarkCase& c) {
  mot += c.tracking.summary;
  if (c.person) {
    person += c.person->summary;
    person_hypotheses += c.person->hypotheses_evaluated;
  }
  moving_only += c.tracking.moving_only;
  moving_objects += c.tracking.moving_objects;
  never_moving_objects += c.tracking.still_objects;
  map += c.map;
  // A group's final-map figures sum every case's; one case without them leaves the group
  // without (a partial sum would pass for the whole group).
  if (cases == 0) {
    final_map = c.final_map;
  } else if (final_map && c.final_map) {
    *final_map += *c.final_map;
  } else {
    final_map.reset();
  }
  for (const auto& [name, member] : stage_members()) {
    (times.*member)
        .insert((times.*member).end(), (c.times.*member).begin(), (c.times.*member).end());
  }
  scans += c.scans;
  ++cases;
}

std::vector<Aggregate> group_cases(const std::vector<BenchmarkCase>& cases) {
  Aggregate all_static = named("all static"), all_moving = named("all moving"),
            overall = named("overall");
  Aggregate val_static = named("validation static"), val_moving = named("validation moving"),
            val_overall = named("validation overall");
  for (const BenchmarkCase& c : cases) {
    if (c.validation) {
      (c.moving ? val_moving : val_static).add(c);
      val_overall.add(c);
    } else {
      (c.moving ? all_moving : all_static).add(c);
      overall.add(c);
    }
  }
  std::vector<Aggregate> groups;
  const bool s1 = all_static.cases > 0, m1 = all_moving.cases > 0;
  const bool s2 = val_static.cases > 0, m2 = val_moving.cases > 0;
  if (s1) groups.push_back(all_static);
  if (m1) groups.push_back(all_moving);
  if (s1 && m1) groups.push_back(overall);
  if (s2) groups.push_back(val_static);
  if (m2) groups.push_back(val_moving);
  if (s2 && m2) groups.push_back(val_overall);
  return groups;
}

}  // namespace ringtrack::experiment
