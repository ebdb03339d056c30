#include "rgbdslam/mapping/binary_vocabulary.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "rgbdslam/synth/scene.h"
#include "rgbdslam/tracking/feature_relocaliser.h"
#include "rgbdslam/util/hamming.h"

namespace rgbdslam {
namespace {

constexpr int kVocabDescriptorBytes = kBinaryDescriptorBytes;

int vocabHamming(const uint8_t* a, const uint8_t* b) { return hamming256(a, b); }

// The bitwise majority of the rows 'members' of 'descriptors' (ties give 0).
cv::Mat majorityOf(const cv::Mat& descriptors, const std::vector<int>& members) {
  std::vector<int> ones(kVocabDescriptorBytes * 8, 0);
  for (int row : members) {
    const uint8_t* d = descriptors.ptr<uint8_t>(row);
    for (int bit = 0; bit < kVocabDescriptorBytes * 8; ++bit) ones[bit] += (d[bit / 8] >> (7 - bit % 8)) & 1;
  }
  cv::Mat centre(1, kVocabDescriptorBytes, CV_8UC1, cv::Scalar(0));
  for (int bit = 0; bit < kVocabDescriptorBytes * 8; ++bit) {
    if (2 * ones[bit] > static_cast<int>(members.size())) centre.at<uint8_t>(0, bit / 8) |= 1 << (7 - bit % 8);
  }
  return centre;
}

// k-means++ seeding on Hamming distance: the first centre at random, each next one with a
// probability proportional to the squared distance to the nearest centre so far.
std::vector<cv::Mat> seedCentres(const cv::Mat& descriptors, const std::vector<int>& rows, int k,
                                 std::mt19937_64* rng) {
  std::vector<cv::Mat> centres;
  std::uniform_int_distribution<size_t> first(0, rows.size() - 1);
  centres.push_back(descriptors.row(rows[first(*rng)]).clone());
  std::vector<double> nearest2(rows.size(), 1e300);
  while (static_cast<int>(centres.size()) < k) {
    double total = 0;
    for (size_t i = 0; i < rows.size(); ++i) {
      const double d = vocabHamming(descriptors.ptr<uint8_t>(rows[i]), centres.back().ptr<uint8_t>());
      nearest2[i] = std::min(nearest2[i], d * d);
      total += nearest2[i];
    }
    if (total <= 0) break;  // every row equals a centre already
    double pick = std::uniform_real_distribution<double>(0, total)(*rng);
    size_t chosen = rows.size() - 1;
    for (size_t i = 0; i < rows.size(); ++i) {
      pick -= nearest2[i];
      if (pick <= 0) {
        chosen = i;
        break;
      }
    }
    centres.push_back(descriptors.row(rows[chosen]).clone());
  }
  return centres;
}

int nearestCentre(const uint8_t* d, const std::vector<cv::Mat>& centres) {
  int best = 0, best_distance = INT32_MAX;
  for (size_t c = 0; c < centres.size(); ++c) {
    const int distance = vocabHamming(d, centres[c].ptr<uint8_t>());
    if (distance < best_distance) best_distance = distance, best = static_cast<int>(c);
  }
  return best;
}

}  // namespace

void BinaryVocabulary::split(int node, const cv::Mat& descriptors, const std::vector<int>& rows, int level,
                             const BinaryVocabularyOptions& options, std::mt19937_64* rng) {
  std::vector<cv::Mat> centres;
  std::vector<std::vector<int>> clusters;
  if (static_cast<int>(rows.size()) <= options.branching) {
    for (int row : rows) {
      centres.push_back(descriptors.row(row).clone());
      clusters.push_back({row});
    }
  } else {
    centres = seedCentres(descriptors, rows, options.branching, rng);
    std::vector<int> assignment(rows.size(), -1);
    for (int iteration = 0; iteration < options.iterations; ++iteration) {
      bool changed = false;
      for (size_t i = 0; i < rows.size(); ++i) {
        const int c = nearestCentre(descriptors.ptr<uint8_t>(rows[i]), centres);
        changed |= c != assignment[i];
        assignment[i] = c;
      }
      clusters.assign(centres.size(), {});
      for (size_t i = 0; i < rows.size(); ++i) clusters[static_cast<size_t>(assignment[i])].push_back(rows[i]);
      if (!changed) break;
      for (size_t c = 0; c < centres.size(); ++c) {
        if (!clusters[c].empty()) centres[c] = majorityOf(descriptors, clusters[c]);
      }
    }
  }
  for (size_t c = 0; c < centres.size(); ++c) {
    if (clusters[c].empty()) continue;
    const int child = static_cast<int>(nodes_.size());
    nodes_.push_back(Node{centres[c], {}, -1});
    nodes_[static_cast<size_t>(node)].children.push_back(child);
    if (level + 1 < options.levels && clusters[c].size() > 1) {
      split(child, descriptors, clusters[c], level + 1, options, rng);
    } else {
      nodes_[static_cast<size_t>(child)].word = static_cast<int>(idf_.size());
      idf_.push_back(0.f);
    }
  }
}

BinaryVocabulary BinaryVocabulary::train(const cv::Mat& descriptors, const std::vector<int>& image_of_row,
                                         const BinaryVocabularyOptions& options) {
  BinaryVocabulary vocabulary;
  vocabulary.nodes_.push_back(Node{});
  if (descriptors.rows == 0) return vocabulary;
  std::vector<int> rows(static_cast<size_t>(descriptors.rows));
  for (int i = 0; i < descriptors.rows; ++i) rows[static_cast<size_t>(i)] = i;
  std::mt19937_64 rng(options.seed);
  vocabulary.split(0, descriptors, rows, 0, options, &rng);
  // idf = ln(N / n_i): N training images, n_i of them with word i.
  std::vector<std::vector<int>> images_of_word(vocabulary.idf_.size());
  for (int i = 0; i < descriptors.rows; ++i) {
    images_of_word[static_cast<size_t>(vocabulary.word(descriptors.ptr<uint8_t>(i)))].push_back(
        image_of_row[static_cast<size_t>(i)]);
  }
  const int images = *std::max_element(image_of_row.begin(), image_of_row.end()) + 1;
  for (size_t w = 0; w < images_of_word.size(); ++w) {
    std::vector<int>& ids = images_of_word[w];
    std::sort(ids.begin(), ids.end());
    const auto n = std::unique(ids.begin(), ids.end()) - ids.begin();
    vocabulary.idf_[w] = n > 0 ? static_cast<float>(std::log(static_cast<double>(images) / n)) : 0.f;
  }
  return vocabulary;
}

int BinaryVocabulary::word(const uint8_t* descriptor) const {
  int node = 0;
  while (!nodes_[static_cast<size_t>(node)].children.empty()) {
    int best = -1, best_distance = INT32_MAX;
    for (int child : nodes_[static_cast<size_t>(node)].children) {
      const int distance = vocabHamming(descriptor, nodes_[static_cast<size_t>(child)].centre.ptr<uint8_t>());
      if (distance < best_distance) best_distance = distance, best = child;
    }
    node = best;
  }
  return nodes_[static_cast<size_t>(node)].word;
}

BowVector BinaryVocabulary::bag(const cv::Mat& descriptors) const {
  BowVector bag;
  if (descriptors.rows == 0 || idf_.empty()) return bag;
  std::vector<int> words(static_cast<size_t>(descriptors.rows));
  for (int i = 0; i < descriptors.rows; ++i) words[static_cast<size_t>(i)] = word(descriptors.ptr<uint8_t>(i));
  std::sort(words.begin(), words.end());
  double total = 0;
  for (size_t i = 0; i < words.size();) {
    size_t j = i;
    while (j < words.size() && words[j] == words[i]) ++j;
    const double weight = static_cast<double>(j - i) * idf_[static_cast<size_t>(words[i])];
    if (weight > 0) bag.emplace_back(words[i], static_cast<float>(weight)), total += weight;
    i = j;
  }
  for (auto& [w, weight] : bag) weight = static_cast<float>(weight / total);
  return bag;
}

double BinaryVocabulary::score(const BowVector& a, const BowVector& b) {
  // For L1-normalised non-negative bags, 1 - |a - b|_1 / 2 = sum over common words of min.
  double s = 0;
  for (size_t i = 0, j = 0; i < a.size() && j < b.size();) {
    if (a[i].first < b[j].first) {
      ++i;
    } else if (b[j].first < a[i].first) {
      ++j;
    } else {
      s += std::min(a[i].second, b[j].second);
      ++i, ++j;
    }
  }
  return s;
}

const BinaryVocabulary& projectVocabulary() {
  // Frames spread over the corridor's first minute and the clean office, every 45th frame.
  static const BinaryVocabulary vocabulary = [] {
    cv::Mat descriptors;
    std::vector<int> image_of_row;
    int image = 0;
    for (const char* spec : {"corridor,frames=1800", "office,effects=none"}) {
      const SyntheticScene scene(*parseSyntheticSpec(spec));
      for (size_t i = 0; i < scene.numFrames(); i += 45) {
        const RgbdFrame frame = scene.render(i);
        cv::Mat grey;
        cv::cvtColor(frame.colour, grey, cv::COLOR_BGR2GRAY);
        const Features3d f = extractFeatures3d(grey, frame.depthMetres(), scene.camera(), FeatureRelocaliserOptions{});
        descriptors.push_back(f.descriptors);
        image_of_row.insert(image_of_row.end(), f.size(), image++);
      }
    }
    return BinaryVocabulary::train(descriptors, image_of_row, BinaryVocabularyOptions{});
  }();
  return vocabulary;
}

bool BowIndex::add(int image, const BowVector& bag) {
  if (image < 0 || contains(image)) return false;
  if (static_cast<size_t>(image) >= indexed_.size()) indexed_.resize(static_cast<size_t>(image) + 1, 0);
  indexed_[static_cast<size_t>(image)] = 1;
  ++images_;
  for (const auto& [word, weight] : bag) {
    if (word < 0) continue;
    if (static_cast<size_t>(word) >= inverted_.size()) inverted_.resize(static_cast<size_t>(word) + 1);
    inverted_[static_cast<size_t>(word)].push_back({image, weight});
  }
  return true;
}

bool BowIndex::remove(int image) {
  if (!contains(image)) return false;
  indexed_[static_cast<size_t>(image)] = 0;
  --images_;
  for (std::vector<Posting>& postings : inverted_) {
    postings.erase(std::remove_if(postings.begin(), postings.end(),
                                  [image](const Posting& p) { return p.image == image; }),
                   postings.end());
  }
  return true;
}

bool BowIndex::contains(int image) const {
  return image >= 0 && static_cast<size_t>(image) < indexed_.size() && indexed_[static_cast<size_t>(image)];
}

size_t BowIndex::bytes() const {
  size_t bytes = indexed_.capacity() + inverted_.capacity() * sizeof(std::vector<Posting>);
  for (const std::vector<Posting>& postings : inverted_) bytes += postings.capacity() * sizeof(Posting);
  return bytes;
}

std::vector<BowIndex::Hit> BowIndex::query(const BowVector& bag, size_t n,
                                           const std::function<bool(int)>& excluded) const {
  // For L1-normalised bags the score is the sum over shared words of the smaller weight.
  std::vector<double> scores(indexed_.size(), 0.0);
  for (const auto& [word, weight] : bag) {
    if (word < 0 || static_cast<size_t>(word) >= inverted_.size()) continue;
    for (const Posting& posting : inverted_[static_cast<size_t>(word)]) {
      scores[static_cast<size_t>(posting.image)] += std::min(weight, posting.weight);
    }
  }
  std::vector<Hit> hits;
  for (size_t i = 0; i < scores.size(); ++i) {
    const int image = static_cast<int>(i);
    if (scores[i] > 0.0 && !(excluded && excluded(image))) hits.push_back({image, scores[i]});
  }
  const size_t keep = std::min(hits.size(), n);
  std::partial_sort(hits.begin(), hits.begin() + static_cast<std::ptrdiff_t>(keep), hits.end(),
                    [](const Hit& a, const Hit& b) { return a.score > b.score || (a.score == b.score && a.image < b.image); });
  hits.resize(keep);
  return hits;
}

}  // namespace rgbdslam
