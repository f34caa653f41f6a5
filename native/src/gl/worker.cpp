// The worker thread: see worker.h.
#include "gl/worker.h"

#include <unistd.h>

#include "glint/errors.h"

namespace glint::gl {

Worker::Worker(const std::string& egl_library) : pid_(getpid()), sync_(std::make_unique<Sync>()) {
  std::exception_ptr failure;
  bool ready = false;
  Sync& sy = *sync_;
  thread_ = std::thread([&, egl_library] {
    try {
      state_ = std::make_unique<GlState>(egl_library);
    } catch (...) {
      failure = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(sy.mu);
      ready = true;
    }
    sy.cv.notify_all();
    if (state_) loop();
  });
  std::unique_lock<std::mutex> lock(sy.mu);
  sy.cv.wait(lock, [&] { return ready; });
  lock.unlock();
  if (failure) {
    thread_.join();
    std::rethrow_exception(failure);
  }
}

Worker::~Worker() {
  if (getpid() != pid_) {
    // A forked child: the thread and the context exist only in the parent,
    // and the copied mutexes and condition variable still record its
    // waiter (destroying them would block forever). Nothing here can be
    // freed safely; the child's exit reclaims it.
    (void)state_.release();
    (void)sync_.release();
    thread_.detach();
    return;
  }
  {
    std::lock_guard<std::mutex> lock(sync_->mu);
    stop_ = true;
  }
  sync_->cv.notify_all();
  if (thread_.joinable()) thread_.join();
}

void Worker::run(const std::function<void(GlState&)>& f) {
  refuse_after_fork();  // the context's thread does not exist in a forked child
  Sync& sy = *sync_;
  std::lock_guard<std::mutex> call(sy.call_mu);  // one caller at a time
  std::unique_lock<std::mutex> lock(sy.mu);
  task_ = &f;
  error_ = nullptr;
  done_ = false;
  sy.cv.notify_all();
  sy.cv.wait(lock, [&] { return done_; });
  if (error_) std::rethrow_exception(error_);
}

void Worker::loop() {
  Sync& sy = *sync_;
  std::unique_lock<std::mutex> lock(sy.mu);
  for (;;) {
    sy.cv.wait(lock, [&] { return stop_ || task_ != nullptr; });
    if (task_) {
      const auto* f = task_;
      lock.unlock();
      std::exception_ptr err;
      try {
        (*f)(*state_);
      } catch (const std::bad_alloc&) {
        err = std::make_exception_ptr(Error("glint GL: out of host memory"));
      } catch (...) {
        err = std::current_exception();
      }
      lock.lock();
      error_ = err;
      task_ = nullptr;
      done_ = true;
      sy.cv.notify_all();
      continue;
    }
    if (stop_) break;
  }
  lock.unlock();
  // GL objects and the context go on the thread they were made on.
  state_.reset();
}

}  // namespace glint::gl
