#include "core/parallel.hh"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>

#include <unistd.h>

namespace hairdyn {

namespace {

/* The workers of parallel_for: threads that sleep on a condition variable between loops.
 * OpenMP's threads spin after a loop (200 ms by default); inside Blender, whose own threads
 * share the cores, the spinning slowed a frame 5× in Blender 3.4, which loads libgomp itself
 * (so the add-on could not ask it to sleep with OMP_WAIT_POLICY). Waking a sleeping thread
 * takes tens of microseconds, though, as long as a whole short loop (a conjugate-gradient
 * iteration's passes take 50–300 µs): so a worker first spins for spin_time after a loop, and
 * the caller as long for the workers to finish, both yielding the core as they spin
 * (spin_while), before either sleeps. A loop hands out its
 * chunks from an atomic counter; the caller works too. A process forked from one that ran
 * loops (Python's multiprocessing) runs its loops alone. */
class ThreadPool {
 public:
  ~ThreadPool() { resize(0); }

  static ThreadPool &get()
  {
    static ThreadPool pool(default_thread_num());
    return pool;
  }

  static int default_thread_num()
  {
    return std::max(1, int(std::thread::hardware_concurrency()));
  }

  int thread_num() const { return int(workers_.size()) + 1; }

  /* Not while a loop runs. */
  void resize(const int thread_num)
  {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread &worker : workers_) {
      worker.join();
    }
    workers_.clear();
    stop_ = false;
    owner_ = getpid();
    for (int i = 1; i < thread_num; i++) {
      workers_.emplace_back([this, seen = generation_.load()]() { work(seen); });
    }
  }

  /* Calls chunk_fn(chunk) for every chunk in [0, chunks), on the workers and the caller. A
   * loop started inside a loop, or while another thread runs one, runs on the caller alone. */
  void run(const int64_t chunks, const ChunkFn &chunk_fn)
  {
    const auto alone = [&]() {
      for (int64_t chunk = 0; chunk < chunks; chunk++) {
        chunk_fn(chunk);
      }
    };
    /* A forked child has none of the workers (fork copies only the calling thread). */
    if (in_loop_ || workers_.empty() || getpid() != owner_) {
      alone();
      return;
    }
    std::unique_lock<std::mutex> running(run_mutex_, std::try_to_lock);
    if (!running.owns_lock()) {
      alone();
      return;
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      job_ = &chunk_fn;
      chunks_ = chunks;
      next_.store(0);
      busy_ = int(workers_.size());
      error_ = nullptr;
      generation_++;
    }
    wake_.notify_all();
    take_chunks();
    spin_while([this]() { return busy_.load(std::memory_order_acquire) != 0; });
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this]() { return busy_.load(std::memory_order_relaxed) == 0; });
    job_ = nullptr;
    if (error_) {
      std::rethrow_exception(error_);
    }
  }

 private:
  explicit ThreadPool(const int thread_num) { resize(thread_num); }

  /* Spins while `busy()` holds, at most spin_time, yielding the core every few pauses: where
   * more threads want the cores than there are (two bakes on one machine, Blender's own
   * threads), a thread that spun without yielding held a core another could use (two LCP
   * runs of 20,000 particles side by side on 2 cores: 143 ms a frame without the yield, 126
   * with it, 131 without spinning). */
  template<typename Busy> static void spin_while(const Busy &busy)
  {
    using clock = std::chrono::steady_clock;
    const clock::time_point until = clock::now() + spin_time;
    while (busy()) {
      for (int i = 0; i < 64; i++) {
#if defined(__x86_64__) || defined(__i386__)
        __builtin_ia32_pause();
#endif
      }
      std::this_thread::yield();
      if (clock::now() > until) {
        return;
      }
    }
  }

  /* `seen`: the loop generation when the worker was made (no loop runs then). */
  void work(uint64_t seen)
  {
    while (true) {
      spin_while([&]() {
        return generation_.load(std::memory_order_acquire) == seen &&
               !stop_.load(std::memory_order_relaxed);
      });
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&]() { return stop_ || generation_ != seen; });
        if (stop_) {
          return;
        }
        seen = generation_;
      }
      take_chunks();
      std::lock_guard<std::mutex> lock(mutex_);
      if (--busy_ == 0) {
        done_.notify_one();
      }
    }
  }

  void take_chunks()
  {
    in_loop_ = true;
    for (int64_t chunk = next_.fetch_add(1); chunk < chunks_; chunk = next_.fetch_add(1)) {
      try {
        (*job_)(chunk);
      }
      catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) {
          error_ = std::current_exception();
        }
      }
    }
    in_loop_ = false;
  }

  std::vector<std::thread> workers_;
  pid_t owner_ = 0; /* the process the workers run in */
  std::mutex run_mutex_; /* one loop at a time */
  std::mutex mutex_;     /* guards what follows but next_ */
  std::condition_variable wake_, done_;
  const ChunkFn *job_ = nullptr;
  int64_t chunks_ = 0;
  std::atomic<int64_t> next_{0};
  std::atomic<int> busy_{0}; /* workers not yet done with the current loop */
  /* Written under mutex_; atomic, so that the spinning threads may read them without it. */
  std::atomic<uint64_t> generation_{0};
  std::atomic<bool> stop_{false};
  static constexpr std::chrono::microseconds spin_time{50};
  std::exception_ptr error_;
  static thread_local bool in_loop_;
};

thread_local bool ThreadPool::in_loop_ = false;

}  // namespace

void run_chunks(const int64_t chunks, const ChunkFn &chunk_fn)
{
  ThreadPool::get().run(chunks, chunk_fn);
}

void set_thread_num(const int thread_num)
{
  ThreadPool &pool = ThreadPool::get();
  const int wanted = thread_num > 0 ? thread_num : ThreadPool::default_thread_num();
  if (wanted != pool.thread_num()) {
    pool.resize(wanted);
  }
}

int thread_num()
{
  return ThreadPool::get().thread_num();
}

}  // namespace hairdyn
