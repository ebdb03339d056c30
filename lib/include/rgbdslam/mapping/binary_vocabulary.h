#pragma once
// A bag of binary words (Galvez-Lopez and Tardos, DBoW2) for 32-byte ORB descriptors: a
// tree of k-majority clusters (k-means with Hamming distance; a centre is the bitwise
// majority of its members), 'branching' children per node, 'levels' deep; the leaves are
// the words. A descriptor's word is found by descending to the nearest child at each level
// (branching * levels Hamming distances). Each word weighs by its inverse document
// frequency over the training images, idf = ln(N / n_i); an image's bag is its words' term
// frequency times idf, L1-normalised, and two bags score 1 - |a - b|_1 / 2 in [0, 1].
//
// Where the vocabulary comes from: trainBinaryVocabulary() on descriptors of any images,
// deterministic for a seed; projectVocabulary() trains the one the project uses, at first
// use, from ORB features of frames it renders itself (the synthetic corridor and office:
// not the room or the flight, on which place recognition is measured). Nothing is
// downloaded or read from a file. Cost of projectVocabulary(): ~1-2 s once per process
// (rendering ~40 frames and clustering ~20000 descriptors); memory ~40 kB for 1000 words.
#include <cstdint>
#include <functional>
#include <random>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace rgbdslam {

struct BinaryVocabularyOptions {
  int branching = 10;         // children per node (k of k-majority)
  int levels = 3;             // depth of the tree: at most branching^levels words
  int iterations = 10;        // k-majority iterations per node at most
  uint64_t seed = 20261125;   // seeding of the clusters (k-means++ on Hamming distance)
};

// Sparse bag: (word, weight) sorted by word; weights sum to 1.
using BowVector = std::vector<std::pair<int, float>>;

class BinaryVocabulary {
 public:
  // From 'descriptors' (CV_8UC1, one 32-byte row per descriptor), and the training image each
  // row came from ('image_of_row', same length) for the idf weights.
  static BinaryVocabulary train(const cv::Mat& descriptors, const std::vector<int>& image_of_row,
                                const BinaryVocabularyOptions& options);

  int words() const { return static_cast<int>(idf_.size()); }
  int word(const uint8_t* descriptor) const;  // the leaf a descriptor descends to
  // The bag of an image's descriptors (rows of 'descriptors'); empty when there are none.
  BowVector bag(const cv::Mat& descriptors) const;
  // 1 - |a - b|_1 / 2 in [0, 1] for L1-normalised bags (1: the same words in the same shares).
  static double score(const BowVector& a, const BowVector& b);

 private:
  struct Node {
    cv::Mat centre;              // 1 x 32 CV_8UC1
    std::vector<int> children;   // node indices; empty at a leaf
    int word = -1;               // at a leaf
  };
  std::vector<Node> nodes_;      // nodes_[0] is the root (no centre)
  std::vector<float> idf_;       // per word

  void split(int node, const cv::Mat& descriptors, const std::vector<int>& rows, int level,
             const BinaryVocabularyOptions& options, std::mt19937_64* rng);
};

// The project's vocabulary (see above), trained once per process on first use; thread-safe.
const BinaryVocabulary& projectVocabulary();

// An inverted index of bags (DBoW2's inverted file): per word, the images that have it and
// its weight there. A query scores every image that shares a word with it, by the bags'
// similarity (BinaryVocabulary::score, accumulated word by word), without touching the rest.
// Images are the caller's non-negative ids (keyframe ids, database entries).
// Memory: 8 bytes per (image, word): 1.2 kB an image of the flight (up to 500 ORB features;
// bench_place_recognition, BM_RelocalisationRanking's index_kB). Time: add() O(words of the bag); query() O(postings of its words + the
// largest id); remove() scans every posting (O(all postings): ~0.3 ms at 1000 images), since
// the index keeps no bags.
class BowIndex {
 public:
  struct Hit {
    int image = -1;
    double score = 0.0;  // BinaryVocabulary::score of the two bags, in [0, 1]
  };

  // Adds 'bag' as image 'image' (>= 0, not in the index yet: false otherwise).
  bool add(int image, const BowVector& bag);
  bool remove(int image);  // false if it is not in the index
  bool contains(int image) const;
  size_t size() const { return images_; }
  size_t bytes() const;  // the postings' memory

  // The best 'n' images sharing a word with 'bag', by score then smaller id; 'excluded'
  // (may be empty) drops images from the result.
  std::vector<Hit> query(const BowVector& bag, size_t n,
                         const std::function<bool(int)>& excluded = {}) const;

 private:
  struct Posting {
    int image = 0;
    float weight = 0.f;
  };
  std::vector<std::vector<Posting>> inverted_;  // per word, grown to the largest word seen
  std::vector<uint8_t> indexed_;                // per image id: 1 while in the index
  size_t images_ = 0;
};

}  // namespace rgbdslam
