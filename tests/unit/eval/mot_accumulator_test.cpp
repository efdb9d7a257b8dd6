// CLEAR MOT accumulator: published py-motmetrics cases, hand-made MT/PT/ML, fragmentation,
// switch and IDF1 cases, and a brute-force oracle for the global id assignment.

#include "ringtrack/eval/mot_accumulator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::eval {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
using Ids = std::vector<std::int64_t>;

Eigen::MatrixXd mat(Eigen::Index rows, Eigen::Index cols, std::initializer_list<double> v) {
  Eigen::MatrixXd m(rows, cols);
  auto it = v.begin();
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) m(i, j) = *it++;
  }
  return m;
}

void empty_frame(MotAccumulator& acc) {
  acc.update({}, {}, Eigen::MatrixXd(0, 0));
}

// py-motmetrics test_mota_motp (rows = objects, columns = hypotheses).
MotAccumulator six_frames(MotOptions options = {}) {
  MotAccumulator acc(options);
  acc.update({}, Ids{1, 2}, Eigen::MatrixXd(0, 2));
  acc.update(Ids{1, 2}, {}, Eigen::MatrixXd(2, 0));
  acc.update(Ids{1, 2}, Ids{1, 2}, mat(2, 2, {1, 0.5, 0.3, 1}));
  acc.update(Ids{1, 2}, Ids{1, 2}, mat(2, 2, {0.2, kInf, kInf, 0.1}));
  acc.update(Ids{1, 2}, Ids{1, 2}, mat(2, 2, {5, 1, 1, 5}));
  empty_frame(acc);
  return acc;
}

// py-motmetrics test_ids.
MotAccumulator seven_frames(MotOptions options = {}) {
  MotAccumulator acc(options);
  empty_frame(acc);
  acc.update(Ids{1, 2}, Ids{1, 2}, mat(2, 2, {1, 0, 0, 1}));
  acc.update(Ids{1, 2}, Ids{1, 2}, mat(2, 2, {0.4, kInf, kInf, 0.4}));
  acc.update(Ids{1, 2}, Ids{1, 2}, mat(2, 2, {0, 1, 1, 0}));
  acc.update(Ids{1, 2}, Ids{2, 3}, mat(2, 2, {1, 0, 0.4, 0.7}));
  acc.update(Ids{1, 3}, Ids{2, 3}, mat(2, 2, {1, 0, 0.4, 0.7}));
  empty_frame(acc);
  return acc;
}

TEST(MotAccumulator, PublishedSixFrameCase) {
  MotOptions options;
  options.threshold = 100.0;
  options.record_events = true;
  const MotAccumulator acc = six_frames(options);
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.frames, 6);
  EXPECT_EQ(s.matches, 4);
  EXPECT_EQ(s.switches, 2);
  EXPECT_EQ(s.false_positives, 2);
  EXPECT_EQ(s.misses, 2);
  EXPECT_EQ(s.gt_presences, 8);
  EXPECT_EQ(s.hypothesis_presences, 8);
  EXPECT_DOUBLE_EQ(s.mota(), 0.25);
  EXPECT_NEAR(s.motp(), 11.1 / 6.0, 1e-12);
  EXPECT_EQ(s.gt_objects, 2);
  EXPECT_EQ(s.hypotheses, 2);
  // Frame 4 (index 4): the previous pairs (1,1) and (2,2) are kept at distance 5 although the
  // crossed pairs would cost 1 + 1.
  int kept = 0;
  for (const MotEvent& e : acc.events()) {
    if (e.frame == 4) {
      EXPECT_EQ(e.type, MotEventType::kMatch);
      EXPECT_EQ(e.object_id, e.hypothesis_id);
      EXPECT_DOUBLE_EQ(e.distance, 5.0);
      ++kept;
    }
  }
  EXPECT_EQ(kept, 2);
}

TEST(MotAccumulator, PublishedSevenFrameCase) {
  MotOptions options;
  options.threshold = 100.0;
  const MotSummary s = seven_frames(options).summary();
  EXPECT_EQ(s.frames, 7);
  EXPECT_EQ(s.matches, 7);
  EXPECT_EQ(s.switches, 3);
  EXPECT_EQ(s.false_positives, 0);
  EXPECT_EQ(s.misses, 0);
  EXPECT_EQ(s.gt_presences, 10);
  EXPECT_NEAR(s.mota(), 0.7, 1e-12);
  EXPECT_NEAR(s.motp(), 0.16, 1e-12);
  EXPECT_EQ(s.gt_objects, 3);
  EXPECT_EQ(s.hypotheses, 3);
  EXPECT_EQ(s.fragmentations, 0);
  EXPECT_EQ(s.mostly_tracked, 3);
}

TEST(MotAccumulator, DefaultInfiniteThresholdGivesTheSameNumbers) {
  const MotSummary s = six_frames().summary();
  EXPECT_EQ(s.matches, 4);
  EXPECT_EQ(s.switches, 2);
}

TEST(MotAccumulator, SequencesAreSummedNotAveraged) {
  MotSummary total = six_frames().summary();
  total += seven_frames().summary();
  EXPECT_EQ(total.matches, 11);
  EXPECT_EQ(total.switches, 5);
  EXPECT_EQ(total.gt_presences, 18);
  EXPECT_EQ(total.gt_objects, 5);
  EXPECT_DOUBLE_EQ(total.mota(), 1.0 - 9.0 / 18.0);  // not (0.25 + 0.7) / 2
  EXPECT_NEAR(total.motp(), (11.1 + 1.6) / 16.0, 1e-12);
}

TEST(MotAccumulator, ThresholdRuleAtTheBoundary) {
  for (const ThresholdRule rule : {ThresholdRule::kBelow, ThresholdRule::kAtMost}) {
    MotOptions options;
    options.threshold = 0.5;
    options.rule = rule;
    MotAccumulator acc(options);
    acc.update(Ids{1}, Ids{7}, mat(1, 1, {0.5}));
    const MotSummary s = acc.summary();
    if (rule == ThresholdRule::kBelow) {
      EXPECT_EQ(s.matches, 0);
      EXPECT_EQ(s.misses, 1);
      EXPECT_EQ(s.false_positives, 1);
    } else {
      EXPECT_EQ(s.matches, 1);
      EXPECT_EQ(s.misses, 0);
    }
  }
}

TEST(MotAccumulator, PreviousPairIsDroppedBeyondThreshold) {
  MotOptions options;
  options.threshold = 0.5;
  options.record_events = true;
  MotAccumulator acc(options);
  acc.update(Ids{1}, Ids{10, 11}, mat(1, 2, {0.1, 0.3}));
  // Last partner 10 is now 0.6 away (beyond the threshold): 11 takes over, an ID switch.
  acc.update(Ids{1}, Ids{10, 11}, mat(1, 2, {0.6, 0.2}));
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.matches, 1);
  EXPECT_EQ(s.switches, 1);
  EXPECT_EQ(s.false_positives, 2);
  EXPECT_EQ(acc.events().back().type, MotEventType::kFalsePositive);
}

TEST(MotAccumulator, SwitchIsAgainstTheLastMatchEvenAcrossGaps) {
  MotOptions options;
  options.threshold = 1.0;
  options.record_events = true;
  MotAccumulator acc(options);
  acc.update(Ids{1}, Ids{10}, mat(1, 1, {0.1}));  // match 1-10
  acc.update(Ids{1}, {}, Eigen::MatrixXd(1, 0));  // miss
  empty_frame(acc);                               // object absent
  acc.update(Ids{1}, Ids{10}, mat(1, 1, {0.2}));  // same partner: match, no switch
  acc.update(Ids{1}, {}, Eigen::MatrixXd(1, 0));  // miss
  acc.update(Ids{1}, Ids{11}, mat(1, 1, {0.2}));  // new partner after a gap: switch
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.matches, 2);
  EXPECT_EQ(s.switches, 1);
  EXPECT_EQ(s.misses, 2);
  EXPECT_EQ(s.fragmentations, 2);
}

TEST(MotAccumulator, LastPartnerIsReclaimedAfterGapOverCheaperAlternative) {
  MotOptions options;
  options.threshold = 1.0;
  options.record_events = true;
  MotAccumulator acc(options);
  acc.update(Ids{1}, Ids{10}, mat(1, 1, {0.5}));
  acc.update(Ids{1}, {}, Eigen::MatrixXd(1, 0));
  // 10 was 1's last partner (two frames ago): kept at 0.9 although 11 is at 0.1.
  acc.update(Ids{1}, Ids{10, 11}, mat(1, 2, {0.9, 0.1}));
  ASSERT_EQ(acc.events().size(), 4u);
  EXPECT_EQ(acc.events()[2].type, MotEventType::kMatch);
  EXPECT_EQ(acc.events()[2].hypothesis_id, 10);
  EXPECT_EQ(acc.events()[3].type, MotEventType::kFalsePositive);
}

TEST(MotAccumulator, ConflictingClaimsOnOneHypothesisGoToTheMostRecentMatch) {
  MotOptions options;
  options.threshold = 1.0;
  options.record_events = true;
  MotAccumulator acc(options);
  acc.update(Ids{1}, Ids{10}, mat(1, 1, {0.1}));  // 1-10
  acc.update(Ids{2}, Ids{10}, mat(1, 1, {0.1}));  // 2-10 (object 1 absent)
  // Both claim 10; object 2's match is more recent, so 2 keeps it although 1 is closer.
  acc.update(Ids{1, 2}, Ids{10}, mat(2, 1, {0.05, 0.3}));
  const MotEvent& e = acc.events()[2];
  EXPECT_EQ(e.type, MotEventType::kMatch);
  EXPECT_EQ(e.object_id, 2);
  EXPECT_EQ(acc.events()[3].type, MotEventType::kMiss);
  EXPECT_EQ(acc.events()[3].object_id, 1);
  // Same frame, objects listed in the other order: same result.
  MotAccumulator swapped(options);
  swapped.update(Ids{1}, Ids{10}, mat(1, 1, {0.1}));
  swapped.update(Ids{2}, Ids{10}, mat(1, 1, {0.1}));
  swapped.update(Ids{2, 1}, Ids{10}, mat(2, 1, {0.3, 0.05}));
  EXPECT_EQ(swapped.events()[2].object_id, 2);
}

TEST(MotAccumulator, HungarianMaximisesPairsThenMinimisesDistance) {
  MotOptions options;
  options.threshold = 1.0;
  MotAccumulator acc(options);
  // Greedy nearest would take (1,10) at 0.1 and leave 2 unmatched; optimum pairs both.
  acc.update(Ids{1, 2}, Ids{10, 11}, mat(2, 2, {0.1, 0.6, 0.7, kInf}));
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.matches, 2);
  EXPECT_NEAR(s.distance_sum, 1.3, 1e-12);
}

TEST(MotAccumulator, MostlyTrackedPartiallyTrackedMostlyLost) {
  // Objects 1..5 present in 10, 10, 10, 10 and 5 frames, tracked (by the hypothesis of the same
  // id) in 8 (80 % -> MT), 7 (PT), 2 (20 % -> PT), 1 (ML) and 0 (ML) of them.
  const std::vector<int> tracked = {8, 7, 2, 1, 0};
  const std::vector<int> present = {10, 10, 10, 10, 5};
  MotAccumulator acc;
  for (int f = 0; f < 10; ++f) {
    Ids objects;
    Ids hypotheses;
    for (std::size_t k = 0; k < tracked.size(); ++k) {
      if (f < present[k]) objects.push_back(static_cast<std::int64_t>(k + 1));
      if (f < tracked[k]) hypotheses.push_back(static_cast<std::int64_t>(k + 1));
    }
    Eigen::MatrixXd d(static_cast<Eigen::Index>(objects.size()),
                      static_cast<Eigen::Index>(hypotheses.size()));
    for (Eigen::Index i = 0; i < d.rows(); ++i) {
      for (Eigen::Index j = 0; j < d.cols(); ++j) {
        d(i, j) = objects[static_cast<std::size_t>(i)] == hypotheses[static_cast<std::size_t>(j)]
                      ? 0.0
                      : kInf;
      }
    }
    acc.update(objects, hypotheses, d);
  }
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.mostly_tracked, 1);
  EXPECT_EQ(s.partially_tracked, 2);
  EXPECT_EQ(s.mostly_lost, 2);
  EXPECT_EQ(s.gt_objects, 5);
  EXPECT_DOUBLE_EQ(s.mostly_tracked_ratio(), 0.2);
  EXPECT_DOUBLE_EQ(s.partially_tracked_ratio(), 0.4);
  EXPECT_DOUBLE_EQ(s.mostly_lost_ratio(), 0.4);
  EXPECT_EQ(s.false_positives, 0);
  EXPECT_EQ(s.matches, 18);
  EXPECT_EQ(s.misses, 45 - 18);
}

TEST(MotAccumulator, FragmentationsCountInterruptionsBetweenMatches) {
  // Per frame: M = matched, x = missed, - = absent. Pattern x M M x M x x M - M x x.
  // Interruptions bounded by matches: frame 3 and frames 5-6 -> 2; leading and trailing misses
  // and the absent frame do not count.
  const std::string pattern = "xMMxMxxM-Mxx";
  MotAccumulator acc;
  for (const char c : pattern) {
    if (c == 'M') {
      acc.update(Ids{1}, Ids{1}, mat(1, 1, {0.0}));
    } else if (c == 'x') {
      acc.update(Ids{1}, {}, Eigen::MatrixXd(1, 0));
    } else {
      empty_frame(acc);
    }
  }
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.fragmentations, 2);
  EXPECT_EQ(s.matches, 5);
  EXPECT_EQ(s.misses, 6);
  EXPECT_EQ(s.partially_tracked, 1);  // 5 of 11 present frames
}

TEST(MotAccumulator, SwitchWithoutMissIsNoFragmentation) {
  MotAccumulator acc;
  acc.update(Ids{1}, Ids{1}, mat(1, 1, {0.0}));
  acc.update(Ids{1}, Ids{2}, mat(1, 1, {0.0}));
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.switches, 1);
  EXPECT_EQ(s.fragmentations, 0);
}

TEST(MotAccumulator, IdF1UsesTheOptimalNotTheGreedyAssignment) {
  // Pairable frames: o1-h10 in 0..5 (6), o1-h11 in 0..4 (5), o2-h10 in 5..9 (5), never o2-h11.
  // Greedy (largest overlap first) takes o1-h10 = 6; the optimum o1-h11 + o2-h10 = 10.
  MotOptions options;
  options.threshold = 1.0;
  MotAccumulator acc(options);
  for (int f = 0; f < 10; ++f) {
    Eigen::MatrixXd d = Eigen::MatrixXd::Constant(2, 2, kInf);
    if (f <= 5) d(0, 0) = 0.5;
    if (f <= 4) d(0, 1) = 0.5;
    if (f >= 5) d(1, 0) = 0.5;
    acc.update(Ids{1, 2}, Ids{10, 11}, d);
  }
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.id_true_positives, 10);
  EXPECT_EQ(s.id_false_negatives, 10);
  EXPECT_EQ(s.id_false_positives, 10);
  EXPECT_DOUBLE_EQ(s.idf1(), 0.5);
  EXPECT_DOUBLE_EQ(s.idp(), 0.5);
  EXPECT_DOUBLE_EQ(s.idr(), 0.5);
}

TEST(MotAccumulator, IdF1OfOneObjectHandedOverBetweenTwoHypotheses) {
  MotAccumulator acc;
  for (int f = 0; f < 10; ++f) acc.update(Ids{1}, Ids{f < 6 ? 10 : 11}, mat(1, 1, {0.0}));
  const MotSummary s = acc.summary();
  EXPECT_EQ(s.id_true_positives, 6);
  EXPECT_EQ(s.id_false_negatives, 4);
  EXPECT_EQ(s.id_false_positives, 4);
  EXPECT_DOUBLE_EQ(s.idf1(), 0.6);
  EXPECT_EQ(s.switches, 1);
}

// Oracle: IDTP by trying every injective object -> hypothesis map.
std::int64_t brute_force_idtp(const std::vector<std::vector<std::int64_t>>& overlap) {
  const std::size_t n = overlap.size();
  const std::size_t m = overlap.empty() ? 0 : overlap[0].size();
  std::int64_t best = 0;
  std::vector<char> used(m, 0);
  std::function<void(std::size_t, std::int64_t)> rec = [&](std::size_t i, std::int64_t sum) {
    if (i == n) {
      best = std::max(best, sum);
      return;
    }
    rec(i + 1, sum);
    for (std::size_t j = 0; j < m; ++j) {
      if (used[j] != 0) continue;
      used[j] = 1;
      rec(i + 1, sum + overlap[i][j]);
      used[j] = 0;
    }
  };
  rec(0, 0);
  return best;
}

TEST(MotAccumulator, RandomSequencesAgainstOracles) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const int n_obj = 1 + trial % 4;
    const int n_hyp = 1 + (trial / 4) % 5;
    MotOptions options;
    options.threshold = 0.6;
    MotAccumulator acc(options);
    std::vector<std::vector<std::int64_t>> overlap(static_cast<std::size_t>(n_obj),
                                                   std::vector<std::int64_t>(n_hyp, 0));
    std::int64_t gt_presences = 0;
    std::int64_t hyp_frames = 0;
    for (int f = 0; f < 15; ++f) {
      Ids objects;
      Ids hypotheses;
      for (int o = 0; o < n_obj; ++o) {
        if (unit(rng) < 0.8) objects.push_back(o);
      }
      for (int h = 0; h < n_hyp; ++h) {
        if (unit(rng) < 0.7) hypotheses.push_back(100 + h);
      }
      Eigen::MatrixXd d(static_cast<Eigen::Index>(objects.size()),
                        static_cast<Eigen::Index>(hypotheses.size()));
      for (Eigen::Index i = 0; i < d.rows(); ++i) {
        for (Eigen::Index j = 0; j < d.cols(); ++j) {
          d(i, j) = unit(rng) < 0.1 ? kInf : unit(rng);
          if (d(i, j) < 0.6) {
            ++overlap[static_cast<std::size_t>(objects[static_cast<std::size_t>(i)])]
                     [static_cast<std::size_t>(hypotheses[static_cast<std::size_t>(j)] - 100)];
          }
        }
      }
      gt_presences += d.rows();
      hyp_frames += d.cols();
      acc.update(objects, hypotheses, d);
    }
    const MotSummary s = acc.summary();
    ASSERT_EQ(s.gt_presences, gt_presences);
    ASSERT_EQ(s.hypothesis_presences, hyp_frames);
    ASSERT_EQ(s.true_positives() + s.misses, s.gt_presences);
    ASSERT_EQ(s.true_positives() + s.false_positives, s.hypothesis_presences);
    ASSERT_EQ(s.mostly_tracked + s.partially_tracked + s.mostly_lost, s.gt_objects);
    ASSERT_EQ(s.id_true_positives, brute_force_idtp(overlap));
    ASSERT_EQ(s.id_true_positives + s.id_false_negatives, gt_presences);
    ASSERT_EQ(s.id_true_positives + s.id_false_positives, hyp_frames);
  }
}

TEST(MotAccumulator, EmptyAccumulatorGivesNaNRatios) {
  const MotSummary s = MotAccumulator().summary();
  EXPECT_TRUE(std::isnan(s.mota()));
  EXPECT_TRUE(std::isnan(s.motp()));
  EXPECT_TRUE(std::isnan(s.idf1()));
  EXPECT_EQ(s.gt_objects, 0);
}

TEST(MotAccumulator, BadInputThrows) {
  MotAccumulator acc;
  EXPECT_THROW(acc.update(Ids{1, 1}, {}, Eigen::MatrixXd(2, 0)), core::InputError);
  EXPECT_THROW(acc.update(Ids{1}, Ids{2, 2}, Eigen::MatrixXd::Zero(1, 2)), core::InputError);
  EXPECT_THROW(acc.update(Ids{1}, Ids{2}, Eigen::MatrixXd::Zero(2, 1)), core::InputError);
  EXPECT_THROW(acc.update(Ids{1}, Ids{2}, mat(1, 1, {-0.1})), core::InputError);
  MotOptions bad;
  bad.threshold = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(MotAccumulator{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace ringtrack::eval
