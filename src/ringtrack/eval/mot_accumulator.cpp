#include "ringtrack/eval/mot_accumulator.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <stdexcept>
#include <string>

#include "ringtrack/core/error.hpp"
#include "ringtrack/eval/assignment.hpp"

namespace ringtrack::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double ratio(std::int64_t numerator, std::int64_t denominator) {
  return denominator == 0 ? kNaN
                          : static_cast<double>(numerator) / static_cast<double>(denominator);
}

void require_unique(std::span<const std::int64_t> ids, const char* what, std::int64_t frame) {
  std::vector<std::int64_t> sorted(ids.begin(), ids.end());
  std::sort(sorted.begin(), sorted.end());
  const auto dup = std::adjacent_find(sorted.begin(), sorted.end());
  if (dup != sorted.end()) {
    throw core::InputError("MOT accumulator: duplicate " + std::string(what) + " id " +
                           std::to_string(*dup) + " in frame " + std::to_string(frame));
  }
}

// Union-find over object and hypothesis indices, to split the id assignment into components.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  std::size_t find(std::size_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(std::size_t a, std::size_t b) { parent_[find(a)] = find(b); }

 private:
  std::vector<std::size_t> parent_;
};

}  // namespace

double MotSummary::mota() const {
  if (gt_presences == 0) return kNaN;
  return 1.0 - static_cast<double>(misses + false_positives + switches) /
                   static_cast<double>(gt_presences);
}
double MotSummary::motp() const {
  return true_positives() == 0 ? kNaN : distance_sum / static_cast<double>(true_positives());
}
double MotSummary::horizontal_motp() const {
  return offset_pairs == 0 ? kNaN : horizontal_distance_sum / static_cast<double>(offset_pairs);
}
double MotSummary::mean_vertical_error() const {
  return offset_pairs == 0 ? kNaN : vertical_error_sum / static_cast<double>(offset_pairs);
}
double MotSummary::recall() const {
  return ratio(true_positives(), gt_presences);
}
double MotSummary::precision() const {
  return ratio(true_positives(), hypothesis_presences);
}
double MotSummary::mostly_tracked_ratio() const {
  return ratio(mostly_tracked, gt_objects);
}
double MotSummary::partially_tracked_ratio() const {
  return ratio(partially_tracked, gt_objects);
}
double MotSummary::mostly_lost_ratio() const {
  return ratio(mostly_lost, gt_objects);
}
double MotSummary::idf1() const {
  return ratio(2 * id_true_positives,
               2 * id_true_positives + id_false_positives + id_false_negatives);
}
double MotSummary::idp() const {
  return ratio(id_true_positives, id_true_positives + id_false_positives);
}
double MotSummary::idr() const {
  return ratio(id_true_positives, id_true_positives + id_false_negatives);
}

MotSummary& MotSummary::operator+=(const MotSummary& o) {
  frames += o.frames;
  gt_presences += o.gt_presences;
  hypothesis_presences += o.hypothesis_presences;
  matches += o.matches;
  switches += o.switches;
  false_positives += o.false_positives;
  misses += o.misses;
  fragmentations += o.fragmentations;
  distance_sum += o.distance_sum;
  offset_pairs += o.offset_pairs;
  horizontal_distance_sum += o.horizontal_distance_sum;
  vertical_error_sum += o.vertical_error_sum;
  gt_objects += o.gt_objects;
  hypotheses += o.hypotheses;
  mostly_tracked += o.mostly_tracked;
  partially_tracked += o.partially_tracked;
  mostly_lost += o.mostly_lost;
  id_true_positives += o.id_true_positives;
  id_false_positives += o.id_false_positives;
  id_false_negatives += o.id_false_negatives;
  return *this;
}

MotAccumulator::MotAccumulator(MotOptions options) : options_(options) {
  if (std::isnan(options_.threshold) || options_.threshold < 0.0) {
    throw std::invalid_argument("MotAccumulator: threshold must be a non-negative number");
  }
}

bool MotAccumulator::pairable(double distance) const {
  if (!std::isfinite(distance)) return false;
  return options_.rule == ThresholdRule::kBelow ? distance < options_.threshold
                                                : distance <= options_.threshold;
}

void MotAccumulator::record(MotEventType type, std::int64_t object_id, std::int64_t hypothesis_id,
                            double distance) {
  if (options_.record_events) {
    events_.push_back({counts_.frames, type, object_id, hypothesis_id, distance});
  }
}

void MotAccumulator::check_frame(std::span<const std::int64_t> object_ids,
                                 std::span<const std::int64_t> hypothesis_ids,
                                 const Eigen::MatrixXd& distances,
                                 std::span<const std::uint8_t> dont_care) const {
  const std::int64_t frame = counts_.frames;
  const auto n_obj = static_cast<Eigen::Index>(object_ids.size());
  const auto n_hyp = static_cast<Eigen::Index>(hypothesis_ids.size());
  if (distances.rows() != n_obj || distances.cols() != n_hyp) {
    throw core::InputError("MOT accumulator: frame " + std::to_string(frame) + " has " +
                           std::to_string(n_obj) + " objects and " + std::to_string(n_hyp) +
                           " hypotheses but a " + std::to_string(distances.rows()) + "x" +
                           std::to_string(distances.cols()) + " distance matrix");
  }
  if (!dont_care.empty() && dont_care.size() != object_ids.size()) {
    throw core::InputError("MOT accumulator: frame " + std::to_string(frame) + " has " +
                           std::to_string(n_obj) + " objects but " +
                           std::to_string(dont_care.size()) + " don't-care flags");
  }
  require_unique(object_ids, "object", frame);
  require_unique(hypothesis_ids, "hypothesis", frame);
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    for (Eigen::Index j = 0; j < n_hyp; ++j) {
      if (distances(i, j) < 0.0) {
        throw core::InputError("MOT accumulator: negative distance between object " +
                               std::to_string(object_ids[static_cast<std::size_t>(i)]) +
                               " and hypothesis " +
                               std::to_string(hypothesis_ids[static_cast<std::size_t>(j)]) +
                               " in frame " + std::to_string(frame));
      }
    }
  }
}

void MotAccumulator::count_unmatched(std::span<const std::int64_t> object_ids,
                                     std::span<const std::int64_t> hypothesis_ids,
                                     const Eigen::MatrixXd& usable,
                                     std::span<const std::uint8_t> dont_care,
                                     const std::vector<Eigen::Index>& row_match,
                                     const std::vector<char>& col_taken,
                                     const std::vector<char>& col_ignored) {
  const auto n_obj = static_cast<Eigen::Index>(object_ids.size());
  const auto n_hyp = static_cast<Eigen::Index>(hypothesis_ids.size());
  const auto ignored_object = [&](Eigen::Index i) {
    return !dont_care.empty() && dont_care[static_cast<std::size_t>(i)] != 0;
  };
  // Don't-care objects and the hypotheses matched to them are not counted.
  std::int64_t counted_objects = 0;
  std::int64_t counted_hypotheses = 0;
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    if (ignored_object(i)) continue;
    ++counted_objects;
    ObjectState& s = objects_[object_ids[static_cast<std::size_t>(i)]];
    ++s.frames_present;
    if (row_match[static_cast<std::size_t>(i)] != kUnassigned) {
      ++s.frames_tracked;
      if (s.missed_since_match) ++counts_.fragmentations;
      s.tracked_before = true;
      s.missed_since_match = false;
    } else {
      ++counts_.misses;
      record(MotEventType::kMiss, object_ids[static_cast<std::size_t>(i)], -1, kNaN);
      if (s.tracked_before) s.missed_since_match = true;
    }
  }
  for (Eigen::Index j = 0; j < n_hyp; ++j) {
    if (col_ignored[static_cast<std::size_t>(j)] != 0) continue;
    ++counted_hypotheses;
    ++hypothesis_frames_[hypothesis_ids[static_cast<std::size_t>(j)]];
    if (col_taken[static_cast<std::size_t>(j)] == 0) {
      ++counts_.false_positives;
      record(MotEventType::kFalsePositive, -1, hypothesis_ids[static_cast<std::size_t>(j)], kNaN);
    }
  }
  // Overlaps for the id metrics, between counted objects and counted hypothesis presences.
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    if (ignored_object(i)) continue;
    for (Eigen::Index j = 0; j < n_hyp; ++j) {
      if (col_ignored[static_cast<std::size_t>(j)] != 0 || std::isnan(usable(i, j))) continue;
      ++overlap_[{object_ids[static_cast<std::size_t>(i)],
                  hypothesis_ids[static_cast<std::size_t>(j)]}];
    }
  }
  counts_.gt_presences += counted_objects;
  counts_.hypothesis_presences += counted_hypotheses;
}

std::vector<Eigen::Index> MotAccumulator::keepers(std::span<const std::int64_t> hypothesis_ids,
                                                  const std::vector<ObjectState*>& state,
                                                  const Eigen::MatrixXd& usable) const {
  const auto n_hyp = static_cast<Eigen::Index>(hypothesis_ids.size());
  const auto n_obj = static_cast<Eigen::Index>(state.size());
  std::unordered_map<std::int64_t, Eigen::Index> col_of_hypothesis;
  for (Eigen::Index j = 0; j < n_hyp; ++j) {
    col_of_hypothesis.emplace(hypothesis_ids[static_cast<std::size_t>(j)], j);
  }
  // An object stays with the hypothesis it was last matched to when both are present and
  // pairable. When several objects claim one hypothesis, the most recent match wins (at most one
  // object was matched to it in any given frame, so there is no tie).
  std::vector<Eigen::Index> keeper(static_cast<std::size_t>(n_hyp), kUnassigned);
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    const ObjectState& s = *state[static_cast<std::size_t>(i)];
    if (!s.last_hypothesis) continue;
    const auto it = col_of_hypothesis.find(*s.last_hypothesis);
    if (it == col_of_hypothesis.end() || std::isnan(usable(i, it->second))) continue;
    Eigen::Index& k = keeper[static_cast<std::size_t>(it->second)];
    if (k == kUnassigned ||
        state[static_cast<std::size_t>(k)]->last_match_frame < s.last_match_frame) {
      k = i;
    }
  }
  return keeper;
}

std::vector<MotPair> MotAccumulator::update(std::span<const std::int64_t> object_ids,
                                            std::span<const std::int64_t> hypothesis_ids,
                                            const Eigen::MatrixXd& distances,
                                            std::span<const std::uint8_t> dont_care) {
  check_frame(object_ids, hypothesis_ids, distances, dont_care);
  const std::int64_t frame = counts_.frames;
  const auto n_obj = static_cast<Eigen::Index>(object_ids.size());
  const auto n_hyp = static_cast<Eigen::Index>(hypothesis_ids.size());
  const auto ignored_object = [&](Eigen::Index i) {
    return !dont_care.empty() && dont_care[static_cast<std::size_t>(i)] != 0;
  };

  // Pairable entries, with NaN for the rest.
  const Eigen::MatrixXd usable =
      distances.unaryExpr([this](double d) { return pairable(d) ? d : kNaN; });

  std::vector<Eigen::Index> row_match(static_cast<std::size_t>(n_obj), kUnassigned);
  std::vector<char> col_taken(static_cast<std::size_t>(n_hyp), 0);
  std::vector<char> col_ignored(static_cast<std::size_t>(n_hyp), 0);  // matched to don't-care
  std::vector<MotPair> counted;
  std::vector<ObjectState*> state(static_cast<std::size_t>(n_obj));
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    state[static_cast<std::size_t>(i)] = &objects_[object_ids[static_cast<std::size_t>(i)]];
  }

  const auto commit = [&](Eigen::Index i, Eigen::Index j) {
    const std::int64_t o = object_ids[static_cast<std::size_t>(i)];
    const std::int64_t h = hypothesis_ids[static_cast<std::size_t>(j)];
    ObjectState& s = *state[static_cast<std::size_t>(i)];
    const bool is_switch = s.last_hypothesis.has_value() && *s.last_hypothesis != h;
    const double d = usable(i, j);
    if (ignored_object(i)) {
      col_ignored[static_cast<std::size_t>(j)] = 1;
      record(MotEventType::kIgnored, o, h, d);
    } else if (is_switch) {
      ++counts_.switches;
      record(MotEventType::kSwitch, o, h, d);
    } else {
      ++counts_.matches;
      record(MotEventType::kMatch, o, h, d);
    }
    if (!ignored_object(i)) {
      counts_.distance_sum += d;
      counted.push_back({i, j});
    }
    s.last_hypothesis = h;
    s.last_match_frame = frame;
    row_match[static_cast<std::size_t>(i)] = j;
    col_taken[static_cast<std::size_t>(j)] = 1;
  };

  // 1. Keep correspondences (keepers); 2. the rest.
  const std::vector<Eigen::Index> keeper = keepers(hypothesis_ids, state, usable);
  for (Eigen::Index j = 0; j < n_hyp; ++j) {
    const Eigen::Index i = keeper[static_cast<std::size_t>(j)];
    if (i != kUnassigned) commit(i, j);
  }

  // 2. The rest: most pairs, then least total distance.
  Eigen::MatrixXd rest = usable;
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    if (row_match[static_cast<std::size_t>(i)] != kUnassigned) rest.row(i).setConstant(kNaN);
  }
  for (Eigen::Index j = 0; j < n_hyp; ++j) {
    if (col_taken[static_cast<std::size_t>(j)] != 0) rest.col(j).setConstant(kNaN);
  }
  const std::vector<Eigen::Index> assigned = max_matching_min_cost(rest);
  for (Eigen::Index i = 0; i < n_obj; ++i) {
    const Eigen::Index j = assigned[static_cast<std::size_t>(i)];
    if (j != kUnassigned) commit(i, j);
  }

  // 3. Misses, per-object tracking history; 4. false positives.
  count_unmatched(object_ids, hypothesis_ids, usable, dont_care, row_match, col_taken, col_ignored);
  ++counts_.frames;
  return counted;
}

MotSummary MotAccumulator::summary() const {
  MotSummary out = counts_;
  out.hypotheses = static_cast<std::int64_t>(hypothesis_frames_.size());
  for (const auto& [id, s] : objects_) {
    if (s.frames_present == 0) continue;  // only ever don't-care
    ++out.gt_objects;
    // Integer comparisons: tracked/present >= 0.8 and < 0.2 without rounding.
    if (5 * s.frames_tracked >= 4 * s.frames_present) {
      ++out.mostly_tracked;
    } else if (5 * s.frames_tracked < s.frames_present) {
      ++out.mostly_lost;
    } else {
      ++out.partially_tracked;
    }
  }

  // Global id assignment (Ristani et al. 2016): one-to-one object <-> hypothesis maximising the
  // frames in which the pair is pairable; solved per connected component of the overlap graph.
  std::map<std::int64_t, std::size_t> object_index;
  std::map<std::int64_t, std::size_t> hypothesis_index;
  for (const auto& [pair, count] : overlap_) {
    object_index.emplace(pair.first, 0);
    hypothesis_index.emplace(pair.second, 0);
  }
  std::size_t next = 0;
  for (auto& [id, index] : object_index) index = next++;
  for (auto& [id, index] : hypothesis_index) index = next++;
  DisjointSets sets(next);
  for (const auto& [pair, count] : overlap_) {
    sets.unite(object_index.at(pair.first), hypothesis_index.at(pair.second));
  }
  struct Component {
    std::vector<std::int64_t> objects;
    std::vector<std::int64_t> hypotheses;
  };
  std::map<std::size_t, Component> components;
  for (const auto& [id, index] : object_index) components[sets.find(index)].objects.push_back(id);
  for (const auto& [id, index] : hypothesis_index) {
    components[sets.find(index)].hypotheses.push_back(id);
  }
  std::int64_t idtp = 0;
  for (const auto& [root, c] : components) {
    Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(c.objects.size()),
                                                 static_cast<Eigen::Index>(c.hypotheses.size()));
    for (std::size_t a = 0; a < c.objects.size(); ++a) {
      for (std::size_t b = 0; b < c.hypotheses.size(); ++b) {
        const auto it = overlap_.find({c.objects[a], c.hypotheses[b]});
        if (it != overlap_.end()) {
          cost(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b)) =
              -static_cast<double>(it->second);
        }
      }
    }
    const std::vector<Eigen::Index> assignment = min_cost_assignment(cost);
    for (std::size_t a = 0; a < assignment.size(); ++a) {
      if (assignment[a] != kUnassigned) {
        idtp += static_cast<std::int64_t>(-cost(static_cast<Eigen::Index>(a), assignment[a]));
      }
    }
  }
  out.id_true_positives = idtp;
  out.id_false_negatives = out.gt_presences - idtp;
  out.id_false_positives = out.hypothesis_presences - idtp;
  return out;
}

}  // namespace ringtrack::eval
