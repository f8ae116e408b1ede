/* The thread pool under parallel_for (core/parallel.hh): every chunk of every loop runs once,
 * whether a worker finds the next loop while it still spins or has gone to sleep; results do
 * not depend on the thread count; a chunk's exception reaches the caller and leaves the pool
 * usable; a loop inside a loop runs on its caller. */
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/parallel.hh"

using namespace hairdyn;

namespace {

/* Restores the default thread count when a test ends. */
struct Threads {
  explicit Threads(const int num) { set_thread_num(num); }
  ~Threads() { set_thread_num(0); }
};

}  // namespace

TEST(Parallel, EveryChunkOfBackToBackLoopsRunsOnce)
{
  const Threads threads(2);
  constexpr int64_t size = 64, grain = 4;
  std::vector<std::atomic<int>> runs(size);
  for (int loop = 0; loop < 3000; loop++) {
    parallel_for(size, grain, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        runs[size_t(i)].fetch_add(1);
      }
    });
    /* Gaps shorter and longer than the workers spin before sleeping (50 µs), so that loops
     * start both while they spin and after they slept. */
    if (loop % 7 == 0) {
      std::this_thread::sleep_for(std::chrono::microseconds(loop % 3 == 0 ? 200 : 20));
    }
  }
  for (const std::atomic<int> &count : runs) {
    EXPECT_EQ(count.load(), 3000);
  }
}

TEST(Parallel, SumsDoNotDependOnTheThreadCount)
{
  const auto sum = [](const int num) {
    const Threads threads(num);
    return parallel_sum(100000, 256, [](const IndexRange range) {
      double s = 0.0;
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        s += 1.0 / double(i + 1);
      }
      return s;
    });
  };
  const double one = sum(1);
  EXPECT_EQ(sum(2), one);
  EXPECT_EQ(sum(4), one);
}

TEST(Parallel, AChunksExceptionReachesTheCallerAndThePoolGoesOn)
{
  const Threads threads(2);
  EXPECT_THROW(parallel_for(1000, 10,
                            [](const IndexRange range) {
                              if (range.start == 500) {
                                throw std::runtime_error("chunk 50");
                              }
                            }),
               std::runtime_error);
  std::atomic<int64_t> items{0};
  parallel_for(1000, 10, [&](const IndexRange range) { items.fetch_add(range.size); });
  EXPECT_EQ(items.load(), 1000);
}

TEST(Parallel, ALoopInsideALoopRunsOnItsCaller)
{
  const Threads threads(2);
  std::atomic<int> mismatched{0};
  std::atomic<int64_t> items{0};
  parallel_for(8, 1, [&](const IndexRange) {
    const std::thread::id outer = std::this_thread::get_id();
    parallel_for(100, 10, [&](const IndexRange range) {
      mismatched.fetch_add(std::this_thread::get_id() == outer ? 0 : 1);
      items.fetch_add(range.size);
    });
  });
  EXPECT_EQ(mismatched.load(), 0);
  EXPECT_EQ(items.load(), 800);
}
