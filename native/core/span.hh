#pragma once
/* Non-owning views over contiguous arrays (C++17 has no std::span). Physics kernels take
 * these; `Span` reads, `MutableSpan` writes. Sizes are int64 like Blender's spans. */
#include <cassert>
#include <cstdint>
#include <vector>

namespace hairdyn {

template<typename T> class Span {
 public:
  constexpr Span() = default;
  constexpr Span(const T *data, int64_t size) : data_(data), size_(size) {}
  Span(const std::vector<T> &v) : data_(v.data()), size_(int64_t(v.size())) {}

  constexpr const T *data() const { return data_; }
  constexpr int64_t size() const { return size_; }
  constexpr bool is_empty() const { return size_ == 0; }
  constexpr const T &operator[](int64_t i) const
  {
    assert(i >= 0 && i < size_);
    return data_[i];
  }
  constexpr Span slice(int64_t start, int64_t size) const
  {
    assert(start >= 0 && size >= 0 && start + size <= size_);
    return Span(data_ + start, size);
  }
  constexpr const T *begin() const { return data_; }
  constexpr const T *end() const { return data_ + size_; }
  constexpr const T &last() const { return data_[size_ - 1]; }

 private:
  const T *data_ = nullptr;
  int64_t size_ = 0;
};

template<typename T> class MutableSpan {
 public:
  constexpr MutableSpan() = default;
  constexpr MutableSpan(T *data, int64_t size) : data_(data), size_(size) {}
  MutableSpan(std::vector<T> &v) : data_(v.data()), size_(int64_t(v.size())) {}

  constexpr operator Span<T>() const { return Span<T>(data_, size_); }
  constexpr T *data() const { return data_; }
  constexpr int64_t size() const { return size_; }
  constexpr T &operator[](int64_t i) const
  {
    assert(i >= 0 && i < size_);
    return data_[i];
  }
  constexpr MutableSpan slice(int64_t start, int64_t size) const
  {
    assert(start >= 0 && size >= 0 && start + size <= size_);
    return MutableSpan(data_ + start, size);
  }
  constexpr T *begin() const { return data_; }
  constexpr T *end() const { return data_ + size_; }

 private:
  T *data_ = nullptr;
  int64_t size_ = 0;
};

/* Half-open index range [start, start + size), as Blender's IndexRange. */
struct IndexRange {
  int64_t start = 0;
  int64_t size = 0;
  constexpr int64_t one_after_last() const { return start + size; }
};

}  // namespace hairdyn
