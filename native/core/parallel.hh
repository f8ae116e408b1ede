#pragma once
/* Parallel loops with a grain size. The partition is static, so a result never depends on
 * the thread count or on scheduling: bakes are byte-identical run to run. */
#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "core/span.hh"

namespace hairdyn {

/* A reference to a callable taking a chunk index (no allocation; the callable must outlive
 * the call). */
class ChunkFn {
 public:
  template<typename F, typename = std::enable_if_t<!std::is_same_v<std::decay_t<F>, ChunkFn>>>
  ChunkFn(const F &fn)
      : object_(&fn), call_([](const void *object, const int64_t chunk) {
          (*static_cast<const F *>(object))(chunk);
        })
  {
  }
  void operator()(const int64_t chunk) const { call_(object_, chunk); }

 private:
  const void *object_;
  void (*call_)(const void *, int64_t);
};

/* chunk_fn(chunk) for every chunk in [0, chunks), on the thread pool (parallel.cpp). */
void run_chunks(int64_t chunks, const ChunkFn &chunk_fn);

/* Calls fn(IndexRange) over chunks of at least `grain` items covering [0, size). */
template<typename Fn> void parallel_for(int64_t size, int64_t grain, const Fn &fn)
{
  if (size <= 0) {
    return;
  }
  grain = std::max<int64_t>(grain, 1);
  const int64_t chunks = (size + grain - 1) / grain;
  if (chunks == 1) {
    fn(IndexRange{0, size});
    return;
  }
  run_chunks(chunks, [&](const int64_t chunk) {
    const int64_t start = chunk * grain;
    fn(IndexRange{start, std::min(grain, size - start)});
  });
}

/* fn(range) over the same static chunks as parallel_for, the chunks' results folded with
 * combine(a, b) in chunk order from `identity`: the result does not depend on the thread
 * count either. */
template<typename T, typename Fn, typename Combine>
T parallel_reduce(int64_t size, int64_t grain, const T &identity, const Fn &fn,
                  const Combine &combine)
{
  if (size <= 0) {
    return identity;
  }
  grain = std::max<int64_t>(grain, 1);
  const int64_t chunks = (size + grain - 1) / grain;
  if (chunks == 1) {
    return combine(identity, fn(IndexRange{0, size}));
  }
  std::vector<T> partial(size_t(chunks), identity);
  run_chunks(chunks, [&](const int64_t chunk) {
    const int64_t start = chunk * grain;
    partial[size_t(chunk)] = fn(IndexRange{start, std::min(grain, size - start)});
  });
  T result = identity;
  for (const T &value : partial) {
    result = combine(result, value);
  }
  return result;
}

/* Σ fn(range) in double precision, deterministic as parallel_reduce. */
template<typename Fn> double parallel_sum(int64_t size, int64_t grain, const Fn &fn)
{
  return parallel_reduce(size, grain, 0.0, fn, [](const double a, const double b) { return a + b; });
}

/* Number of threads parallel_for uses; 0 restores the default (all cores). */
void set_thread_num(int thread_num);
int thread_num();

}  // namespace hairdyn
