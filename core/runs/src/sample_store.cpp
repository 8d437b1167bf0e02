#include "spindown/sample_store.hpp"

namespace spindown {

void SampleStore::grow() {
  // Keep [base_, end_ - 1) (the sample being pushed is written after) at the same positions modulo
  // the new, doubled size.
  const std::size_t size = 2 * capacity(), mask = size - 1;
  auto bigger = std::make_unique_for_overwrite<Sample[]>(size);
  for (std::size_t k = base_; k + 1 < end_; ++k) bigger[k & mask] = ring_[k & mask_];
  ring_ = std::move(bigger);
  mask_ = mask;
}

}  // namespace spindown
