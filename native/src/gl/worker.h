// The worker thread that owns the GlState (see gl_backend.cpp for why GL work
// runs on a thread of its own).
#pragma once
#include <sys/types.h>

#include <condition_variable>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "gl/gl_state.h"

namespace glint::gl {

class Worker {
 public:
  explicit Worker(const std::string& egl_library);

  ~Worker();

  // Runs f(state) on the worker thread and waits; exceptions come back here.
  void run(const std::function<void(GlState&)>& f);

 private:
  void loop();

  struct Sync {
    std::mutex call_mu;  // serializes callers
    std::mutex mu;       // guards the task hand-over below
    std::condition_variable cv;
  };

  pid_t pid_;
  std::unique_ptr<Sync> sync_;  // on the heap so a forked child can abandon it
  std::thread thread_;
  const std::function<void(GlState&)>* task_ = nullptr;
  std::exception_ptr error_;
  bool done_ = false;
  bool stop_ = false;
  std::unique_ptr<GlState> state_;
};

}  // namespace glint::gl
