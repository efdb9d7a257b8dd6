#include "ringtrack/eval/tracking_eval.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::eval {
namespace {

// Groups items by frame (ascending), sorts each frame's items by id and rejects duplicate ids.
template <typename T, typename FrameOf>
std::map<std::int64_t, std::vector<const T*>> group_by_frame(const std::vector<const T*>& items,
                                                             FrameOf frame_of, const char* what) {
  std::map<std::int64_t, std::vector<const T*>> frames;
  for (const T* item : items) frames[frame_of(*item)].push_back(item);
  for (auto& [frame, list] : frames) {
    std::sort(list.begin(), list.end(), [](const T* a, const T* b) { return a->id < b->id; });
    for (std::size_t k = 1; k < list.size(); ++k) {
      if (list[k]->id == list[k - 1]->id) {
        throw core::InputError(std::string("evaluation: duplicate ") + what + " id " +
                               std::to_string(list[k]->id) + " in scan/frame " +
                               std::to_string(frame));
      }
    }
  }
  return frames;
}

// Runs the accumulator over the union of frames of both sides. dont_care(object) flags objects
// that are matched but not counted; offset(object, hypothesis) gives the position error of a
// counted correspondence (hypothesis - object) or nullopt when positions have no meaning.
template <typename G, typename H, typename Distance, typename DontCare, typename Offset>
MotSummary accumulate(const std::map<std::int64_t, std::vector<const G*>>& gt,
                      const std::map<std::int64_t, std::vector<const H*>>& hyp,
                      const MotOptions& options, Distance distance, DontCare dont_care,
                      Offset offset) {
  std::set<std::int64_t> frames;
  for (const auto& [frame, list] : gt) frames.insert(frame);
  for (const auto& [frame, list] : hyp) frames.insert(frame);
  MotAccumulator acc(options);
  const std::vector<const G*> no_gt;
  const std::vector<const H*> no_hyp;
  std::vector<std::int64_t> object_ids;
  std::vector<std::int64_t> hypothesis_ids;
  std::vector<std::uint8_t> flags;
  std::int64_t offset_pairs = 0;
  double horizontal_sum = 0.0;
  double vertical_sum = 0.0;
  for (const std::int64_t frame : frames) {
    const auto g_it = gt.find(frame);
    const auto h_it = hyp.find(frame);
    const auto& g = g_it == gt.end() ? no_gt : g_it->second;
    const auto& h = h_it == hyp.end() ? no_hyp : h_it->second;
    object_ids.clear();
    hypothesis_ids.clear();
    flags.clear();
    bool any_dont_care = false;
    for (const G* o : g) {
      object_ids.push_back(o->id);
      flags.push_back(dont_care(*o) ? 1 : 0);
      any_dont_care = any_dont_care || flags.back() != 0;
    }
    for (const H* t : h) hypothesis_ids.push_back(t->id);
    Eigen::MatrixXd d(static_cast<Eigen::Index>(g.size()), static_cast<Eigen::Index>(h.size()));
    for (std::size_t i = 0; i < g.size(); ++i) {
      for (std::size_t j = 0; j < h.size(); ++j) {
        d(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = distance(*g[i], *h[j]);
      }
    }
    const std::vector<MotPair> pairs = acc.update(
        object_ids, hypothesis_ids, d,
        any_dont_care ? std::span<const std::uint8_t>(flags) : std::span<const std::uint8_t>());
    for (const MotPair& p : pairs) {
      const std::optional<Eigen::Vector3d> e = offset(*g[static_cast<std::size_t>(p.object)],
                                                      *h[static_cast<std::size_t>(p.hypothesis)]);
      if (!e) continue;
      ++offset_pairs;
      horizontal_sum += e->head<2>().norm();
      vertical_sum += e->z();
    }
  }
  MotSummary out = acc.summary();
  out.offset_pairs = offset_pairs;
  out.horizontal_distance_sum = horizontal_sum;
  out.vertical_error_sum = vertical_sum;
  return out;
}

// The position that decides whether an object moves: true centre, else centroid, else none.
std::optional<Eigen::Vector3d> motion_position(const GroundTruthObject& o) {
  if (o.true_center_m.allFinite()) return o.true_center_m;
  if (o.points > 0 && o.centroid_m.allFinite()) return o.centroid_m;
  return std::nullopt;
}

}  // namespace

const char* selection_name(HypothesisSelection selection) {
  switch (selection) {
    case HypothesisSelection::kEverDynamic:
      return "dynamic";
    case HypothesisSelection::kPerson:
      return "person";
    case HypothesisSelection::kAll:
      return "all";
  }
  return "dynamic";
}

HypothesisSelection parse_selection(const std::string& name) {
  for (const auto s : {HypothesisSelection::kEverDynamic, HypothesisSelection::kPerson,
                       HypothesisSelection::kAll}) {
    if (name == selection_name(s)) return s;
  }
  throw core::InputError("evaluation: unknown hypothesis selection '" + name +
                         "' (expected dynamic, person or all)");
}

std::vector<std::int64_t> moving_objects(std::span<const GroundTruthObject> ground_truth,
                                         double radius_m) {
  if (!(radius_m >= 0.0) || !std::isfinite(radius_m)) {
    throw core::InputError("evaluation: the moving radius must be a finite distance >= 0 m");
  }
  // First position per id: the lowest scan with a position.
  std::map<std::int64_t, std::pair<std::int64_t, Eigen::Vector2d>> first;
  for (const GroundTruthObject& o : ground_truth) {
    const auto p = motion_position(o);
    if (!p) continue;
    const auto it = first.find(o.id);
    if (it == first.end() || o.scan < it->second.first) first[o.id] = {o.scan, p->head<2>()};
  }
  std::set<std::int64_t> moving;
  for (const GroundTruthObject& o : ground_truth) {
    const auto p = motion_position(o);
    if (p && (p->head<2>() - first.at(o.id).second).norm() > radius_m) moving.insert(o.id);
  }
  return {moving.begin(), moving.end()};
}

TrackingEvalResult evaluate_tracks(std::span<const GroundTruthObject> ground_truth,
                                   std::span<const TrackObservation> tracks,
                                   const TrackingEvalOptions& options) {
  if (options.min_points < 1) {
    throw core::InputError("evaluation: min_points must be at least 1 (got " +
                           std::to_string(options.min_points) + ")");
  }
  if (!(options.threshold_m > 0.0)) {
    throw core::InputError("evaluation: threshold must be a positive distance in metres");
  }
  TrackingEvalResult result;
  std::vector<const GroundTruthObject*> gt;
  for (const GroundTruthObject& o : ground_truth) {
    if (o.class_name != options.target_class || o.points < options.min_points) {
      ++result.gt_rows_skipped;
      continue;
    }
    if (!o.centroid_m.allFinite()) {
      throw core::InputError("evaluation: ground-truth object " + std::to_string(o.id) +
                             " in scan " + std::to_string(o.scan) +
                             " has hit points but a non-finite centroid");
    }
    gt.push_back(&o);
  }
  result.gt_rows_used = static_cast<std::int64_t>(gt.size());

  std::set<std::int64_t> all_ids;
  std::set<std::int64_t> selected_ids;
  for (const TrackObservation& t : tracks) {
    all_ids.insert(t.id);
    const bool selected = options.hypotheses == HypothesisSelection::kAll ||
                          (options.hypotheses == HypothesisSelection::kEverDynamic &&
                           (t.dynamic || t.ever_dynamic)) ||
                          (options.hypotheses == HypothesisSelection::kPerson && t.person);
    if (selected) selected_ids.insert(t.id);
  }
  std::vector<const TrackObservation*> hyp;
  for (const TrackObservation& t : tracks) {
    if (selected_ids.count(t.id) == 0) continue;
    if (!t.position_m.allFinite()) {
      throw core::InputError("evaluation: track " + std::to_string(t.id) + " in scan " +
                             std::to_string(t.scan) + " has a non-finite position");
    }
    hyp.push_back(&t);
  }
  result.hypotheses_total = static_cast<std::int64_t>(all_ids.size());
  result.hypotheses_evaluated = static_cast<std::int64_t>(selected_ids.size());

  const auto gt_presences = group_by_frame(
      gt, [](const GroundTruthObject& o) { return o.scan; }, "ground-truth object");
  const auto hyp_frames = group_by_frame(
      hyp, [](const TrackObservation& t) { return t.scan; }, "track");
  MotOptions mot;
  mot.threshold = options.threshold_m;
  mot.rule = ThresholdRule::kBelow;
  const auto distance = [](const GroundTruthObject& o, const TrackObservation& t) {
    return (o.centroid_m - t.position_m).norm();
  };
  const auto offset = [](const GroundTruthObject& o, const TrackObservation& t) {
    return std::optional<Eigen::Vector3d>(t.position_m - o.centroid_m);
  };
  result.summary = accumulate(
      gt_presences, hyp_frames, mot, distance, [](const GroundTruthObject&) { return false; },
      offset);

  const std::vector<std::int64_t> moving = moving_objects(ground_truth, options.moving_radius_m);
  const auto is_moving = [&moving](std::int64_t id) {
    return std::binary_search(moving.begin(), moving.end(), id);
  };
  std::set<std::int64_t> evaluated_ids;
  for (const GroundTruthObject* o : gt) evaluated_ids.insert(o->id);
  for (const std::int64_t id : evaluated_ids)
    ++(is_moving(id) ? result.moving_objects : result.still_objects);
  result.moving_only = accumulate(
      gt_presences, hyp_frames, mot, distance,
      [&is_moving](const GroundTruthObject& o) { return !is_moving(o.id); }, offset);
  return result;
}

double box_iou(const BoxObservation& a, const BoxObservation& b) {
  const double ix =
      std::max(0.0, std::min(a.left + a.width, b.left + b.width) - std::max(a.left, b.left));
  const double iy =
      std::max(0.0, std::min(a.top + a.height, b.top + b.height) - std::max(a.top, b.top));
  const double inter = ix * iy;
  const double uni = a.width * a.height + b.width * b.height - inter;
  return uni > 0.0 ? inter / uni : 0.0;
}

MotSummary evaluate_boxes(std::span<const BoxObservation> ground_truth,
                          std::span<const BoxObservation> hypotheses, double min_iou) {
  if (!(min_iou > 0.0 && min_iou <= 1.0)) {
    throw core::InputError("evaluation: minimum IoU must be in (0, 1]");
  }
  const auto check = [](const BoxObservation& b, const char* what) {
    const bool finite = std::isfinite(b.left) && std::isfinite(b.top) && std::isfinite(b.width) &&
                        std::isfinite(b.height);
    if (!finite || b.width < 0.0 || b.height < 0.0) {
      throw core::InputError(std::string("evaluation: ") + what + " box of id " +
                             std::to_string(b.id) + " in frame " + std::to_string(b.frame) +
                             " must have finite coordinates and non-negative size");
    }
  };
  std::vector<const BoxObservation*> gt;
  std::vector<const BoxObservation*> hyp;
  for (const BoxObservation& b : ground_truth) {
    check(b, "ground-truth");
    gt.push_back(&b);
  }
  for (const BoxObservation& b : hypotheses) {
    check(b, "hypothesis");
    hyp.push_back(&b);
  }
  const auto frame_of = [](const BoxObservation& b) { return b.frame; };
  MotOptions mot;
  // 1 - IoU <= 1 - min_iou  <=>  IoU >= min_iou (1 - x is exact for x in [0.5, 1]).
  mot.threshold = 1.0 - min_iou;
  mot.rule = ThresholdRule::kAtMost;
  return accumulate(
      group_by_frame(gt, frame_of, "ground-truth"), group_by_frame(hyp, frame_of, "hypothesis"),
      mot, [](const BoxObservation& a, const BoxObservation& b) { return 1.0 - box_iou(a, b); },
      [](const BoxObservation&) { return false; },
      [](const BoxObservation&, const BoxObservation&) {
        return std::optional<Eigen::Vector3d>();
      });
}

}  // namespace ringtrack::eval
