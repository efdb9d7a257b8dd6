// Sequence drivers: ground-truth filters, paper mode, threshold boundary, IoU matching.

#include "ringtrack/eval/tracking_eval.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::eval {
namespace {

GroundTruthObject person(std::int64_t scan, std::int64_t id, double x, std::int64_t points = 10) {
  return {scan, id, "person", points, Eigen::Vector3d(x, 0.0, 0.0)};
}

TrackObservation track(std::int64_t scan, std::int64_t id, double x, bool ever_dynamic) {
  return {scan, id, Eigen::Vector3d(x, 0.0, 0.0), ever_dynamic, ever_dynamic};
}

TEST(EvaluateTracks, FiltersClassAndMinimumPoints) {
  const std::vector<GroundTruthObject> gt = {person(0, 1, 0.0),
                                             {0, 2, "robot", 10, Eigen::Vector3d(5, 0, 0)},
                                             person(0, 3, 9.0, 0),
                                             person(0, 4, 20.0, 2)};
  const std::vector<TrackObservation> tracks = {track(0, 10, 0.1, true)};
  TrackingEvalOptions options;
  options.min_points = 3;
  const TrackingEvalResult r = evaluate_tracks(gt, tracks, options);
  EXPECT_EQ(r.gt_rows_used, 1);
  EXPECT_EQ(r.gt_rows_skipped, 3);
  EXPECT_EQ(r.summary.gt_objects, 1);
  EXPECT_EQ(r.summary.matches, 1);
  EXPECT_EQ(r.summary.misses, 0);
  options.target_class = "robot";
  const TrackingEvalResult robots = evaluate_tracks(gt, tracks, options);
  EXPECT_EQ(robots.summary.gt_objects, 1);
  EXPECT_EQ(robots.summary.matches, 0);
  EXPECT_EQ(robots.summary.misses, 1);
  EXPECT_EQ(robots.summary.false_positives, 1);
}

TEST(EvaluateTracks, PaperModeKeepsEverDynamicHypothesesInAllTheirScans) {
  // Person 1 walks along x; track 11 follows it and is flagged dynamic only from scan 2 on;
  // track 10 is a static false positive and never dynamic.
  std::vector<GroundTruthObject> gt;
  std::vector<TrackObservation> tracks;
  for (std::int64_t s = 0; s < 4; ++s) {
    gt.push_back(person(s, 1, 0.3 * static_cast<double>(s)));
    tracks.push_back(track(s, 11, 0.3 * static_cast<double>(s) + 0.05, s >= 2));
    tracks.push_back(track(s, 10, 7.0, false));
  }
  const TrackingEvalResult paper = evaluate_tracks(gt, tracks);
  EXPECT_EQ(paper.hypotheses_total, 2);
  EXPECT_EQ(paper.hypotheses_evaluated, 1);
  EXPECT_EQ(paper.summary.matches, 4);  // also scans 0 and 1, before 11 turned dynamic
  EXPECT_EQ(paper.summary.false_positives, 0);
  EXPECT_DOUBLE_EQ(paper.summary.mota(), 1.0);
  EXPECT_NEAR(paper.summary.motp(), 0.05, 1e-12);

  TrackingEvalOptions all;
  all.hypotheses = HypothesisSelection::kAll;
  const TrackingEvalResult every = evaluate_tracks(gt, tracks, all);
  EXPECT_EQ(every.hypotheses_evaluated, 2);
  EXPECT_EQ(every.summary.false_positives, 4);
  EXPECT_DOUBLE_EQ(every.summary.mota(), 0.0);
}

// Person mode (issue 10): a person standing all the time is tracked by a hypothesis that is
// never dynamic but flagged person. Paper mode drops that hypothesis, so the standing person is
// a miss in every scan; person mode scores it as a hit. Both keep the same ground truth.
TEST(EvaluateTracks, PersonModeScoresAStandingPersonThatPaperModeMisses) {
  std::vector<GroundTruthObject> gt;
  std::vector<TrackObservation> tracks;
  for (std::int64_t s = 0; s < 10; ++s) {
    gt.push_back(person(s, 1, 0.3 * static_cast<double>(s)));  // walks
    gt.push_back(person(s, 2, 20.0));                          // stands all the time
    // Walker's track: dynamic from scan 3, person from scan 2.
    tracks.push_back({s, 11, Eigen::Vector3d(0.3 * static_cast<double>(s) + 0.05, 0, 0), s >= 3,
                      s >= 3, s >= 2});
    // Stander's track: never dynamic, person from scan 4 (scored in all its scans, as paper
    // mode scores an ever-dynamic id in all its scans).
    tracks.push_back({s, 12, Eigen::Vector3d(20.1, 0, 0), false, false, s >= 4});
    // Person-sized clutter in scans 0-4: never dynamic, flagged person: false positives in
    // person mode.
    if (s < 5) tracks.push_back({s, 13, Eigen::Vector3d(-7.0, 0, 0), false, false, true});
    // A short track never flagged person: in neither mode.
    if (s < 3) tracks.push_back({s, 14, Eigen::Vector3d(9.0, 0, 0), false, false, false});
  }
  const TrackingEvalResult paper = evaluate_tracks(gt, tracks);
  EXPECT_EQ(paper.hypotheses_evaluated, 1);
  EXPECT_EQ(paper.summary.gt_presences, 20);
  EXPECT_EQ(paper.summary.matches, 10);
  EXPECT_EQ(paper.summary.misses, 10);  // the standing person, every scan
  EXPECT_EQ(paper.summary.false_positives, 0);
  EXPECT_DOUBLE_EQ(paper.summary.mota(), 0.5);

  TrackingEvalOptions options;
  options.hypotheses = HypothesisSelection::kPerson;
  const TrackingEvalResult person_mode = evaluate_tracks(gt, tracks, options);
  EXPECT_EQ(person_mode.hypotheses_total, 4);
  EXPECT_EQ(person_mode.hypotheses_evaluated, 3);
  EXPECT_EQ(person_mode.summary.gt_presences, 20);  // the same ground truth
  EXPECT_EQ(person_mode.summary.matches, 20);       // the standing person in all 10 scans
  EXPECT_EQ(person_mode.summary.misses, 0);
  EXPECT_EQ(person_mode.summary.false_positives, 5);  // the clutter
  EXPECT_DOUBLE_EQ(person_mode.summary.mota(), 0.75);
  EXPECT_EQ(person_mode.summary.mostly_tracked, 2);
  EXPECT_EQ(paper.summary.mostly_lost, 1);
}

TEST(EvaluateTracks, SelectionNamesRoundTrip) {
  for (const auto s :
       {HypothesisSelection::kEverDynamic, HypothesisSelection::kPerson, HypothesisSelection::kAll})
    EXPECT_EQ(parse_selection(selection_name(s)), s);
  EXPECT_STREQ(selection_name(HypothesisSelection::kEverDynamic), "dynamic");
  EXPECT_THROW((void)parse_selection("persons"), core::InputError);
}

TEST(EvaluateTracks, DistanceMustBeStrictlyBelowThreshold) {
  const std::vector<GroundTruthObject> gt = {person(0, 1, 0.0), person(1, 1, 0.0)};
  const std::vector<TrackObservation> tracks = {track(0, 5, 0.5, true), track(1, 5, 0.25, true)};
  const TrackingEvalResult r = evaluate_tracks(gt, tracks);
  EXPECT_EQ(r.summary.matches, 1);  // 0.5 m is not below 0.5 m; 0.25 m is
  EXPECT_EQ(r.summary.misses, 1);
  EXPECT_EQ(r.summary.false_positives, 1);
  EXPECT_EQ(r.summary.fragmentations, 0);
}

TEST(EvaluateTracks, RowOrderDoesNotMatter) {
  std::vector<GroundTruthObject> gt = {person(2, 1, 0.0), person(0, 2, 3.0), person(0, 1, 0.0),
                                       person(1, 1, 0.0), person(2, 2, 3.0)};
  std::vector<TrackObservation> tracks = {track(2, 9, 3.1, true), track(0, 8, 0.1, true),
                                          track(0, 9, 3.1, true), track(2, 8, 0.1, true)};
  const MotSummary a = evaluate_tracks(gt, tracks).summary;
  std::reverse(gt.begin(), gt.end());
  std::reverse(tracks.begin(), tracks.end());
  const MotSummary b = evaluate_tracks(gt, tracks).summary;
  EXPECT_EQ(a.matches, 4);
  EXPECT_EQ(a.misses, 1);
  EXPECT_EQ(a.fragmentations, 1);
  EXPECT_EQ(b.matches, a.matches);
  EXPECT_EQ(b.misses, a.misses);
  EXPECT_EQ(b.fragmentations, a.fragmentations);
  EXPECT_EQ(b.frames, 3);
}

TEST(EvaluateTracks, RejectsBadInput) {
  const std::vector<TrackObservation> none;
  EXPECT_THROW((void)evaluate_tracks(std::vector{person(0, 1, 0.0), person(0, 1, 1.0)}, none),
               core::InputError);
  TrackingEvalOptions zero;
  zero.min_points = 0;
  EXPECT_THROW((void)evaluate_tracks({}, none, zero), core::InputError);
  GroundTruthObject nan_centroid = person(0, 1, std::numeric_limits<double>::quiet_NaN());
  EXPECT_THROW((void)evaluate_tracks(std::vector{nan_centroid}, none), core::InputError);
  // A NaN centroid without hit points is skipped, not an error.
  nan_centroid.points = 0;
  EXPECT_NO_THROW((void)evaluate_tracks(std::vector{nan_centroid}, none));
  EXPECT_THROW(
      (void)evaluate_tracks({}, std::vector{track(0, 3, 0.0, true), track(0, 3, 1.0, true)}),
      core::InputError);
}

TEST(BoxIou, HandValues) {
  const BoxObservation a{0, 1, 0.0, 0.0, 10.0, 10.0};
  EXPECT_DOUBLE_EQ(box_iou(a, a), 1.0);
  EXPECT_DOUBLE_EQ(box_iou(a, {0, 2, 5.0, 0.0, 10.0, 10.0}), 50.0 / 150.0);
  EXPECT_DOUBLE_EQ(box_iou(a, {0, 2, 0.0, 0.0, 10.0, 5.0}), 0.5);
  EXPECT_DOUBLE_EQ(box_iou(a, {0, 2, 10.0, 0.0, 10.0, 10.0}), 0.0);  // touching edges
  EXPECT_DOUBLE_EQ(box_iou({0, 1, 0, 0, 0, 0}, {0, 2, 0, 0, 0, 0}), 0.0);
}

TEST(EvaluateBoxes, IoUOfExactlyOneHalfMatches) {
  const std::vector<BoxObservation> gt = {
      {1, 1, 0, 0, 10, 10}, {2, 1, 0, 0, 10, 10}, {3, 1, 0, 0, 10, 10}};
  const std::vector<BoxObservation> hyp = {{1, 7, 0, 0, 10, 5},    // IoU 0.5: match
                                           {2, 7, 5, 0, 10, 10},   // IoU 1/3: no
                                           {3, 8, 1, 0, 10, 10}};  // IoU 9/11: switch
  const MotSummary s = evaluate_boxes(gt, hyp);
  EXPECT_EQ(s.matches, 1);
  EXPECT_EQ(s.switches, 1);
  EXPECT_EQ(s.misses, 1);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_EQ(s.fragmentations, 1);
  EXPECT_NEAR(s.motp(), (0.5 + 2.0 / 11.0) / 2.0, 1e-12);
  EXPECT_THROW((void)evaluate_boxes(gt, std::vector<BoxObservation>{{1, 1, 0, 0, -1, 2}}),
               core::InputError);
  EXPECT_THROW((void)evaluate_boxes(gt, hyp, 0.0), core::InputError);
}

}  // namespace
}  // namespace ringtrack::eval
