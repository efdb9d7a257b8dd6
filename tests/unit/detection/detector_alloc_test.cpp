// Steady-state detect() must not allocate: this test binary counts every operator new.

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "ringtrack/detection/detector.hpp"
#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace {
std::atomic<std::size_t> g_allocations{0};
}  // namespace

// These replace the global allocation functions, pairing operator new with malloc and operator
// delete with free on purpose. g++ 12 cannot see that pairing once inlined (the asan preset's
// -O2 build) and warns -Wmismatched-new-delete about free() of "new"-ed memory; the warning is
// wrong for a replacement allocator, so it is silenced here only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) {
  return operator new(size);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
// The nothrow forms too (std::stable_sort's temporary buffer uses them): left to the runtime's
// own, their memory would reach the free() above, and AddressSanitizer reports that pairing as
// alloc-dealloc-mismatch in every test of this binary.
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t& tag) noexcept {
  return operator new(size, tag);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace ringtrack::detection {
namespace {

TEST(DetectorAllocations, SteadyStateCallsDoNotAllocate) {
  const auto model = core::SensorModel::vlp16();
  const auto ten = sim::render(model, sim::SimpleScene::open_field(10));
  const auto three = sim::render(model, sim::SimpleScene::open_field(3));
  segmentation::Segmenter segmenter{core::SegmentationConfig{}};
  std::vector<std::uint8_t> labels_ten, labels_three;
  segmenter.segment(ten.scan, labels_ten);
  segmenter.segment(three.scan, labels_three);
  const std::vector<Eigen::Vector3f> predictions = {Eigen::Vector3f(5.0f, 1.5f, -2.0f)};
  Detector detector{core::DetectionConfig{}};
  // Warm-up: the largest scan grows every buffer once (and the counter does see that).
  const std::size_t start = g_allocations.load();
  detector.detect(ten.scan, labels_ten, core::Pose{}, predictions);
  detector.detect(three.scan, labels_three, core::Pose{}, predictions);
  EXPECT_GT(g_allocations.load() - start, 10u);
  const std::size_t before = g_allocations.load();
  std::size_t found = 0;
  for (int k = 0; k < 10; ++k) {
    found += detector.detect(ten.scan, labels_ten, core::Pose{}, predictions).size();
    found += detector.detect(three.scan, labels_three, core::Pose{}, predictions).size();
  }
  EXPECT_EQ(g_allocations.load() - before, 0u);
  EXPECT_EQ(found, 10u * (10u + 3u));
}

}  // namespace
}  // namespace ringtrack::detection
