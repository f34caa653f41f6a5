// Reads a fuzzer's bytes as typed values, front to back; past the end every
// read gives zeros, so any input, however short, is a whole request.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace glint::fuzz {

class Bytes {
 public:
  Bytes(const uint8_t* data, size_t size) : p_(data), n_(size) {}

  template <typename T>
  T take() {
    T v{};
    const size_t k = n_ < sizeof(T) ? n_ : sizeof(T);
    std::memcpy(&v, p_, k);
    p_ += k;
    n_ -= k;
    return v;
  }
  // An integer in [lo, hi].
  int in_range(int lo, int hi) {
    return lo + static_cast<int>(take<uint16_t>() % static_cast<unsigned>(hi - lo + 1));
  }
  // Raw float bits: NaN, Inf, denormals and huge values all come through.
  float any_float() { return take<float>(); }
  size_t left() const { return n_; }

 private:
  const uint8_t* p_;
  size_t n_;
};

}  // namespace glint::fuzz
