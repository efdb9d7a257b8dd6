// Evaluation kernels: the Hungarian solver and one accumulator frame (not real-time critical, but
// the global id assignment runs on sequence-sized matrices).

#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "ringtrack/eval/assignment.hpp"
#include "ringtrack/eval/mot_accumulator.hpp"

namespace {

void BM_MinCostAssignment(benchmark::State& state) {
  const auto n = static_cast<Eigen::Index>(state.range(0));
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> value(0.0, 1.0);
  Eigen::MatrixXd cost(n, n);
  for (Eigen::Index i = 0; i < cost.size(); ++i) cost(i) = value(rng);
  for (auto _ : state) benchmark::DoNotOptimize(ringtrack::eval::min_cost_assignment(cost));
}
BENCHMARK(BM_MinCostAssignment)->Arg(10)->Arg(50)->Arg(200);

// 10 people and 12 hypotheses per frame, 20 % of pairs beyond the 0.5 m threshold.
void BM_MotAccumulatorFrame(benchmark::State& state) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> value(0.0, 0.6);
  std::vector<std::int64_t> objects(10);
  std::vector<std::int64_t> hypotheses(12);
  for (std::size_t k = 0; k < objects.size(); ++k) objects[k] = static_cast<std::int64_t>(k);
  for (std::size_t k = 0; k < hypotheses.size(); ++k) {
    hypotheses[k] = static_cast<std::int64_t>(100 + k);
  }
  std::vector<Eigen::MatrixXd> frames(64, Eigen::MatrixXd(10, 12));
  for (auto& d : frames) {
    for (Eigen::Index i = 0; i < d.size(); ++i) d(i) = value(rng);
  }
  ringtrack::eval::MotOptions options;
  options.threshold = 0.5;
  ringtrack::eval::MotAccumulator acc(options);
  std::size_t f = 0;
  for (auto _ : state) acc.update(objects, hypotheses, frames[f++ % frames.size()]);
  benchmark::DoNotOptimize(acc.summary());
}
BENCHMARK(BM_MotAccumulatorFrame);

}  // namespace
