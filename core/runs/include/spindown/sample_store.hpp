#pragma once
// The samples a run detector holds, live and offline: a ring indexed by absolute sample index,
// holding [base(), end()). It doubles when full, each sample staying at its index modulo the new
// size, and forgets its oldest samples only when told (the detector knows which it still needs:
// a lead-in to search, an open coast). Readings are finite: the detector takes no other.
#include <algorithm>
#include <cstddef>
#include <memory>

namespace spindown {

class SampleStore {
 public:
  struct Sample {  // no initializers: a new ring is not written before it is used
    double t, v;
  };
  // The first size: a lab run (30 s at 50 Hz) fits without growing.
  static constexpr std::size_t initial_size = 2048;

  SampleStore() : ring_(std::make_unique_for_overwrite<Sample[]>(initial_size)), mask_(initial_size - 1) {}

  double t(std::size_t i) const { return ring_[i & mask_].t; }
  double v(std::size_t i) const { return ring_[i & mask_].v; }
  const Sample& at(std::size_t i) const { return ring_[i & mask_]; }
  std::size_t base() const { return base_; }  // the oldest sample held
  std::size_t end() const { return end_; }    // the index the next sample gets
  std::size_t size() const { return end_ - base_; }
  std::size_t capacity() const { return mask_ + 1; }

  // Adds s at index end(), growing when full; returns its index.
  std::size_t push(Sample s) {
    const std::size_t i = end_++;
    if (end_ - base_ > capacity()) [[unlikely]] grow();
    ring_[i & mask_] = s;
    return i;
  }
  // Forgets the samples before i (at most all of them).
  void drop_before(std::size_t i) { base_ = std::max(base_, std::min(i, end_)); }

  // For a loop that keeps the ring in locals (a store through a member could alias every double
  // the loop reads): the storage and its mask, valid until the store grows. Such a loop writes
  // samples [end(), e) itself, never beyond capacity() samples held, then calls set_end(e).
  Sample* data() { return ring_.get(); }
  const Sample* data() const { return ring_.get(); }
  std::size_t mask() const { return mask_; }
  void set_end(std::size_t e) { end_ = e; }

 private:
  void grow();

  std::unique_ptr<Sample[]> ring_;
  std::size_t mask_;
  std::size_t base_ = 0, end_ = 0;
};

}  // namespace spindown
