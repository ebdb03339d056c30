#pragma once
// The most recent values of a timing, for medians and percentiles in status reports.
#include <algorithm>
#include <cstddef>
#include <deque>
#include <vector>

namespace rgbdslam {

class RecentSamples {
 public:
  explicit RecentSamples(size_t capacity = 1000) : capacity_(capacity) {}
  void add(double value) {
    values_.push_back(value);
    if (values_.size() > capacity_) values_.pop_front();
  }
  // The q-quantile (0.5: median) of the values held; 0 when there are none.
  double quantile(double q) const {
    if (values_.empty()) return 0.0;
    std::vector<double> sorted(values_.begin(), values_.end());
    const size_t k = static_cast<size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5);
    std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
    return sorted[k];
  }
  double last() const { return values_.empty() ? 0.0 : values_.back(); }
  size_t size() const { return values_.size(); }

 private:
  size_t capacity_;
  std::deque<double> values_;
};

}  // namespace rgbdslam
