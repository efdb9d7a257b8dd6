// Don't-care objects in the accumulator, the "moves at some time" rule, the moving-objects-only
// figures, horizontal MOTP and the vertical error, on hand-made cases computed by hand.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/eval/mot_accumulator.hpp"
#include "ringtrack/eval/tracking_eval.hpp"

namespace ringtrack::eval {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
using Ids = std::vector<std::int64_t>;
using Flags = std::vector<std::uint8_t>;

Eigen::MatrixXd mat(Eigen::Index rows, Eigen::Index cols, std::initializer_list<double> v) {
  Eigen::MatrixXd m(rows, cols);
  auto it = v.begin();
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) m(i, j) = *it++;
  }
  return m;
}

// Object 1 is counted, object 2 is don't-care in every frame.
//   f0: o{1,2} h{10,11}  [[0.1, inf], [inf, 0.2]]  -> (1,10) match; (2,11) ignored
//   f1: o{1,2} h{11,12}  [[inf, inf], [0.2, 0.3]]  -> 2 keeps 11 (ignored); 12 FP although it is
//                                                     within reach of 2; 1 missed
//   f2: o{2}   h{11}     [[0.1]]                   -> ignored: nothing counted
//   f3: o{1}   h{10}     [[0.2]]                   -> match; a fragmentation of 1
TEST(DontCare, HandCountedFrames) {
  MotOptions options;
  options.threshold = 0.5;
  options.record_events = true;
  MotAccumulator acc(options);
  auto pairs = acc.update(Ids{1, 2}, Ids{10, 11}, mat(2, 2, {0.1, kInf, kInf, 0.2}), Flags{0, 1});
  ASSERT_EQ(pairs.size(), 1u);  // only the counted correspondence is returned
  EXPECT_EQ(pairs[0].object, 0);
  EXPECT_EQ(pairs[0].hypothesis, 0);
  pairs = acc.update(Ids{1, 2}, Ids{11, 12}, mat(2, 2, {kInf, kInf, 0.2, 0.3}), Flags{0, 1});
  EXPECT_TRUE(pairs.empty());
  pairs = acc.update(Ids{2}, Ids{11}, mat(1, 1, {0.1}), Flags{1});
  EXPECT_TRUE(pairs.empty());
  pairs = acc.update(Ids{1}, Ids{10}, mat(1, 1, {0.2}), Flags{0});
  ASSERT_EQ(pairs.size(), 1u);

  const MotSummary s = acc.summary();
  EXPECT_EQ(s.frames, 4);
  EXPECT_EQ(s.gt_presences, 3);          // object 1 only
  EXPECT_EQ(s.hypothesis_presences, 3);  // 10, 12, 10; the three presences of 11 are ignored
  EXPECT_EQ(s.matches, 2);
  EXPECT_EQ(s.switches, 0);
  EXPECT_EQ(s.misses, 1);
  EXPECT_EQ(s.false_positives, 1);
  EXPECT_EQ(s.fragmentations, 1);
  EXPECT_NEAR(s.mota(), 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(s.motp(), 0.15, 1e-12);
  EXPECT_EQ(s.gt_objects, 1);
  EXPECT_EQ(s.hypotheses, 2);  // 10 and 12; 11 was only ever ignored
  EXPECT_EQ(s.partially_tracked, 1);
  EXPECT_EQ(s.mostly_tracked + s.mostly_lost, 0);
  // IDTP: (1,10) pairable in f0 and f3.
  EXPECT_EQ(s.id_true_positives, 2);
  EXPECT_EQ(s.id_false_negatives, 1);
  EXPECT_EQ(s.id_false_positives, 1);
  int ignored = 0;
  for (const MotEvent& e : acc.events()) {
    if (e.type == MotEventType::kIgnored) {
      EXPECT_EQ(e.object_id, 2);
      EXPECT_EQ(e.hypothesis_id, 11);
      ++ignored;
    }
  }
  EXPECT_EQ(ignored, 3);

  // The same frames without flags: object 2 is an ordinary object matched three times.
  MotAccumulator plain(options);
  plain.update(Ids{1, 2}, Ids{10, 11}, mat(2, 2, {0.1, kInf, kInf, 0.2}));
  plain.update(Ids{1, 2}, Ids{11, 12}, mat(2, 2, {kInf, kInf, 0.2, 0.3}));
  plain.update(Ids{2}, Ids{11}, mat(1, 1, {0.1}));
  plain.update(Ids{1}, Ids{10}, mat(1, 1, {0.2}));
  const MotSummary p = plain.summary();
  EXPECT_EQ(p.matches, 5);
  EXPECT_EQ(p.misses, 1);
  EXPECT_EQ(p.false_positives, 1);
  EXPECT_EQ(p.gt_presences, 6);
}

// A don't-care object competes in the matching like any object: the cheaper pair wins, and the
// counted object it beat is missed (the restricted figures use the full evaluation's matching).
TEST(DontCare, MatchingIsTheFullEvaluations) {
  MotOptions options;
  options.threshold = 0.5;
  MotAccumulator acc(options);
  acc.update(Ids{1, 2}, Ids{10}, mat(2, 1, {0.3, 0.1}), Flags{0, 1});
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.matches, 0);
  EXPECT_EQ(s.misses, 1);
  EXPECT_EQ(s.false_positives, 0);
  EXPECT_EQ(s.hypothesis_presences, 0);
  EXPECT_TRUE(std::isnan(s.motp()));
  EXPECT_DOUBLE_EQ(s.mota(), 0.0);
}

TEST(DontCare, AllFlagsZeroEqualsNoFlags) {
  MotOptions options;
  options.threshold = 100.0;
  MotAccumulator a(options);
  MotAccumulator b(options);
  const Eigen::MatrixXd d = mat(2, 2, {1, 0.5, 0.3, 1});
  a.update(Ids{1, 2}, Ids{1, 2}, d);
  b.update(Ids{1, 2}, Ids{1, 2}, d, Flags{0, 0});
  EXPECT_EQ(a.summary().matches, b.summary().matches);
  EXPECT_EQ(a.summary().distance_sum, b.summary().distance_sum);
  EXPECT_EQ(a.summary().id_true_positives, b.summary().id_true_positives);
}

TEST(DontCare, WrongFlagCountThrows) {
  MotAccumulator acc;
  EXPECT_THROW(acc.update(Ids{1, 2}, {}, Eigen::MatrixXd(2, 0), Flags{1}), core::InputError);
}

TEST(MotSummary, OffsetsAreSummedAndNaNWithoutPairs) {
  MotSummary a;
  EXPECT_TRUE(std::isnan(a.horizontal_motp()));
  EXPECT_TRUE(std::isnan(a.mean_vertical_error()));
  a.offset_pairs = 2;
  a.horizontal_distance_sum = 0.5;
  a.vertical_error_sum = -0.2;
  MotSummary b;
  b.offset_pairs = 3;
  b.horizontal_distance_sum = 1.0;
  b.vertical_error_sum = 0.7;
  a += b;
  EXPECT_DOUBLE_EQ(a.horizontal_motp(), 1.5 / 5.0);  // not (0.25 + 0.333) / 2
  EXPECT_DOUBLE_EQ(a.mean_vertical_error(), 0.5 / 5.0);
}

GroundTruthObject row(std::int64_t scan, std::int64_t id, Eigen::Vector3d centroid,
                      Eigen::Vector3d true_center = Eigen::Vector3d::Constant(kNaN),
                      std::int64_t points = 10) {
  return {scan, id, "person", points, centroid, true_center};
}

TEST(MovingObjects, LeavingTheDiscIsStrictAndHorizontal) {
  const Eigen::Vector3d o(0, 0, 1);
  const std::vector<GroundTruthObject> gt = {
      // 1: exactly 1 m away: on the circle, has not left the disc.
      row(0, 1, o), row(1, 1, Eigen::Vector3d(0.6, 0.8, 1)),
      // 2: just beyond.
      row(0, 2, o), row(1, 2, Eigen::Vector3d(1.0 + 1e-9, 0, 1)),
      // 3: climbs 5 m (vertical motion is not horizontal motion).
      row(0, 3, o), row(1, 3, Eigen::Vector3d(0, 0, 6)),
      // 4: moves only while hidden: true centres of rows without hit points count.
      row(0, 4, o, o), row(1, 4, Eigen::Vector3d::Constant(kNaN), Eigen::Vector3d(3, 0, 1), 0),
      row(2, 4, o, o),
      // 5: the first position is the lowest scan's, whatever the row order; true centre first
      //    (the centroids alone would not move).
      row(3, 5, o, Eigen::Vector3d(2, 0, 1)), row(1, 5, o, Eigen::Vector3d(0.5, 0, 1)),
      row(2, 5, o, Eigen::Vector3d(0.2, 0, 1))};
  EXPECT_EQ(moving_objects(gt, 1.0), (Ids{2, 4, 5}));
  EXPECT_EQ(moving_objects(gt, 0.0), (Ids{1, 2, 4, 5}));
  EXPECT_EQ(moving_objects(gt, 10.0), Ids{});
  EXPECT_THROW((void)moving_objects(gt, -1.0), core::InputError);
  EXPECT_THROW((void)moving_objects(gt, kNaN), core::InputError);
}

// Four scans, z of every ground-truth centroid 1.0 m:
//   person 1 walks x = 0, 0.5, 1, 1.5 (moves 1.5 m; no true centre: centroids decide)
//   person 2 stands at (5, 0) with a 5 cm true-centre jitter (never moves: don't-care)
//   person 3 stands at x = 10 in scans 0-1, then walks to 11, 12 (stands then walks: moving)
//   track 10 on person 1, offset (0.12, 0.16, +0.1): 3-D sqrt(0.05), x-y 0.2, dz +0.1
//   track 11 on person 2, offset (0, 0.3, -0.2):     3-D sqrt(0.13), x-y 0.3, dz -0.2
//   track 12 on person 3 from scan 1, offset (0.1, 0, 0): 0.1, 0.1, 0
//   track 13 clutter at (20, 0, 1)
TEST(EvaluateTracks, MovingObjectsOnlyByHand) {
  std::vector<GroundTruthObject> gt;
  std::vector<TrackObservation> tracks;
  const double x3[] = {10, 10, 11, 12};
  for (std::int64_t s = 0; s < 4; ++s) {
    const auto sd = static_cast<double>(s);
    const Eigen::Vector3d p1(0.5 * sd, 0, 1);
    const Eigen::Vector3d p2(5, 0, 1);
    const Eigen::Vector3d p3(x3[s], 0, 1);
    gt.push_back(row(s, 1, p1));
    gt.push_back(row(s, 2, p2, Eigen::Vector3d(5 + 0.05 * sd, 0, 0.9)));
    gt.push_back(row(s, 3, p3, Eigen::Vector3d(x3[s], 0, 0.9)));
    tracks.push_back({s, 10, p1 + Eigen::Vector3d(0.12, 0.16, 0.1), true, true});
    tracks.push_back({s, 11, p2 + Eigen::Vector3d(0, 0.3, -0.2), true, true});
    if (s >= 1) tracks.push_back({s, 12, p3 + Eigen::Vector3d(0.1, 0, 0), true, true});
    tracks.push_back({s, 13, Eigen::Vector3d(20, 0, 1), true, true});
  }
  const TrackingEvalResult r = evaluate_tracks(gt, tracks);

  // Full figures: 12 presences, 11 correspondences, 1 miss (person 3, scan 0), 4 FP.
  const MotSummary& f = r.summary;
  EXPECT_EQ(f.gt_presences, 12);
  EXPECT_EQ(f.true_positives(), 11);
  EXPECT_EQ(f.misses, 1);
  EXPECT_EQ(f.false_positives, 4);
  EXPECT_NEAR(f.mota(), 7.0 / 12.0, 1e-12);
  EXPECT_NEAR(f.motp(), (4 * std::sqrt(0.05) + 4 * std::sqrt(0.13) + 0.3) / 11.0, 1e-12);
  EXPECT_NEAR(f.horizontal_motp(), (4 * 0.2 + 4 * 0.3 + 3 * 0.1) / 11.0, 1e-12);
  EXPECT_NEAR(f.mean_vertical_error(), (4 * 0.1 - 4 * 0.2) / 11.0, 1e-12);

  // Moving objects only: persons 1 and 3; person 2 is don't-care, so track 11 is neither a TP
  // nor an FP; the clutter stays an FP.
  EXPECT_EQ(r.moving_objects, 2);
  EXPECT_EQ(r.still_objects, 1);
  const MotSummary& m = r.moving_only;
  EXPECT_EQ(m.gt_presences, 8);
  EXPECT_EQ(m.gt_objects, 2);
  EXPECT_EQ(m.true_positives(), 7);
  EXPECT_EQ(m.misses, 1);
  EXPECT_EQ(m.false_positives, 4);
  EXPECT_EQ(m.hypothesis_presences, 11);
  EXPECT_EQ(m.hypotheses, 3);
  EXPECT_NEAR(m.mota(), 3.0 / 8.0, 1e-12);
  EXPECT_NEAR(m.precision(), 7.0 / 11.0, 1e-12);
  EXPECT_NEAR(m.motp(), (4 * std::sqrt(0.05) + 0.3) / 7.0, 1e-12);
  EXPECT_NEAR(m.horizontal_motp(), 1.1 / 7.0, 1e-12);
  EXPECT_NEAR(m.mean_vertical_error(), 0.4 / 7.0, 1e-12);
  EXPECT_EQ(m.mostly_tracked, 1);     // person 1
  EXPECT_EQ(m.partially_tracked, 1);  // person 3: 3 of 4 scans
}

TEST(EvaluateTracks, EveryObjectMovingGivesTheFullFigures) {
  std::vector<GroundTruthObject> gt;
  std::vector<TrackObservation> tracks;
  for (std::int64_t s = 0; s < 3; ++s) {
    const Eigen::Vector3d p(0.6 * static_cast<double>(s), 0, 1);
    gt.push_back(row(s, 1, p));
    tracks.push_back({s, 7, p + Eigen::Vector3d(0, 0.1, 0.05), true, true});
    tracks.push_back({s, 8, Eigen::Vector3d(9, 9, 1), true, true});
  }
  TrackingEvalOptions options;
  const TrackingEvalResult r = evaluate_tracks(gt, tracks, options);
  EXPECT_EQ(r.moving_objects, 1);
  EXPECT_EQ(r.moving_only.matches, r.summary.matches);
  EXPECT_EQ(r.moving_only.false_positives, r.summary.false_positives);
  EXPECT_EQ(r.moving_only.hypothesis_presences, r.summary.hypothesis_presences);
  EXPECT_EQ(r.moving_only.distance_sum, r.summary.distance_sum);
  EXPECT_NEAR(r.summary.horizontal_motp(), 0.1, 1e-12);
  EXPECT_NEAR(r.summary.mean_vertical_error(), 0.05, 1e-12);
  // A larger radius: the same person never moves; every figure of the restriction is empty and
  // the track on it is ignored, the clutter is still a false positive.
  options.moving_radius_m = 2.0;
  const TrackingEvalResult still = evaluate_tracks(gt, tracks, options);
  EXPECT_EQ(still.moving_objects, 0);
  EXPECT_EQ(still.still_objects, 1);
  EXPECT_EQ(still.moving_only.gt_presences, 0);
  EXPECT_EQ(still.moving_only.false_positives, 3);
  EXPECT_EQ(still.moving_only.hypothesis_presences, 3);
  EXPECT_TRUE(std::isnan(still.moving_only.mota()));
  EXPECT_EQ(still.summary.matches, r.summary.matches);  // the full figures do not change
  options.moving_radius_m = -0.5;
  EXPECT_THROW((void)evaluate_tracks(gt, tracks, options), core::InputError);
}

}  // namespace
}  // namespace ringtrack::eval
