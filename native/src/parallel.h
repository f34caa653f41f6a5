// Row-parallel loops, for the CPU backend and the pipeline's survey. Rays cost very different amounts
// (a sky pixel is free, a grazing floor ray crosses the screen), so rows are
// handed out in small chunks from a shared counter rather than split evenly.
#pragma once
#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <system_error>
#include <thread>
#include <vector>

namespace glint {

inline int resolve_threads(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

// Calls body(y) for every y in [begin, end). What body throws is rethrown
// here, on the caller's thread, once every worker has stopped (rows not yet
// handed out are then skipped): an exception leaving a std::thread would end
// the process. If the system refuses to start a thread, the ones that did
// start share the rows with the caller's thread.
template <class Body>
void parallel_rows(int begin, int end, int threads, Body&& body) {
  const int rows = end - begin;
  if (rows <= 0) return;
  const int n = std::min(resolve_threads(threads), rows);
  if (n <= 1) {
    for (int y = begin; y < end; ++y) body(y);
    return;
  }
  const int chunk = std::max(1, rows / (n * 16));
  std::atomic<int> next{begin};
  std::mutex failure_mu;
  std::exception_ptr failure;
  auto worker = [&]() {
    try {
      for (;;) {
        const int y0 = next.fetch_add(chunk);
        if (y0 >= end) return;
        const int y1 = std::min(end, y0 + chunk);
        for (int y = y0; y < y1; ++y) body(y);
      }
    } catch (...) {
      next.store(end);  // the other workers stop at their next chunk
      std::lock_guard<std::mutex> lock(failure_mu);
      if (!failure) failure = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(n - 1);
  for (int t = 0; t < n - 1; ++t) {
    try {
      pool.emplace_back(worker);
    } catch (const std::system_error&) {
      break;  // e.g. EAGAIN under a process or address-space limit
    }
  }
  worker();
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
}

}  // namespace glint
